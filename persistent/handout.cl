// rtlab — the persistent schedules' shared hand-out code: which pixel a lane takes next, how a
// warp's idle lanes take pixels together, the state a lane keeps for its pixel, the keys hits are
// sorted by, and the phase clocks. Each schedule is a kernel of its own file over this one:
// flat.cl (one loop over rays), nested.cl (a loop over pixels around the megakernel's loop over
// rays), regrouped.cl (the flat loop with each step's hits sorted by pattern before shading), and
// the bounce loop, a wavefront inside one launch (wavefront/bounce/bounce.cl).
//
// Pixels are handed out in strips (Persistent_PixelOf; 4x16 unless the schedule says 16x8), so
// that lanes taking pixels at the same time get neighbours, whose rays take the same paths
// through the scene, and a warp's next pixels lie below its last ones. On NVIDIA (RT_WARP_PTX) the
// idle lanes of a warp take consecutive pixels with one atomic add.
//
// The per-ray work is the weighted megakernel's (megakernel_sample.cl), and each pixel's rays
// and samples are summed in the same order, so every schedule's image is the same to the bit.
#ifndef RT_PERSIST_HANDOUT_CL
#define RT_PERSIST_HANDOUT_CL
#include "handout_order.h"
#include "megakernel_sample.cl"
#include "phases.h"

// Pixel `k` of the `count` pixels from `first` in row-major order. Whole rows go by strips of
// RT_PERSIST_TILE_W columns and RT_PERSIST_TILE_H rows, row by row inside a strip (bands of TILE_H
// rows, the last band and the last strip of a band cut to fit); anything else (part of one row,
// under --max-launch-ms) goes left to right.
inline int2 Persistent_PixelOf(int k, int first, int count, int width) {
    if (first % width != 0 || count % width != 0) {
        const int p = first + k, y = p / width;
        return (int2)(p - y * width, y);
    }
    int x, y;
    RT_STRIP_PIXEL(k, width, count / width, RT_PERSIST_TILE_W, RT_PERSIST_TILE_H, x, y);
    return (int2)(x, first / width + y);
}

// A kernel whose work-group size is a define tells the compiler so where the host asks
// (RT_REQD_GROUP_SIZE): a compiler that assumes smaller groups otherwise (LLVM's AMDGPU back end:
// 256) builds a kernel that cannot launch in groups of 512. NVIDIA's compiler is not asked: with
// the attribute it built kernels that take at most 256 work-items a group whatever their
// registers; there the host's register cap (-cl-nv-maxrregcount) makes a group fit.
#ifdef RT_REQD_GROUP_SIZE
#define RT_GROUP_LANES(n) __attribute__((reqd_work_group_size(n, 1, 1)))
#else
#define RT_GROUP_LANES(n)
#endif

#ifdef RT_WARP_PTX
// Whether the caller's warp has lanes without a pixel; *wanting gets them (PTX vote.sync.ballot
// among the lanes that run it together). Every lane calls it. The idle lanes take pixels at once:
// waiting for more of them (whole-warp refill, measured until 2026-12) cost more than the
// coherence it bought (persistent/README.md, "What was tried").
inline bool Persistent_Refill(bool idle, uint* wanting) {
    uint active, idleLanes;
    __asm__ volatile("activemask.b32 %0;" : "=r"(active));
    __asm__ volatile("{ .reg .pred q; setp.ne.u32 q, %1, 0; vote.sync.ballot.b32 %0, q, %2; }"
                     : "=r"(idleLanes)
                     : "r"((uint)idle), "r"(active));
    *wanting = idleLanes;
    return idleLanes != 0u;
}

// The lanes of `warp` for which `p` holds; every lane of `warp` must call it.
inline uint Persistent_WarpBallot(bool p, uint warp) {
    uint lanes;
    __asm__ volatile("{ .reg .pred q; setp.ne.u32 q, %1, 0; vote.sync.ballot.b32 %0, q, %2; }"
                     : "=r"(lanes)
                     : "r"((uint)p), "r"(warp));
    return lanes;
}

// Lane `from`'s v, to every lane of `warp` (each of them calls it).
inline int Persistent_WarpShuffle(int v, int from, uint warp) {
    __asm__ volatile("shfl.sync.idx.b32 %0, %1, %2, 0x1f, %3;"
                     : "=r"(v)
                     : "r"(v), "r"(from), "r"(warp));
    return v;
}

// Pixels for the lanes of `wanting` (each of them calls this): one atomic add by the lowest,
// its result passed to the others with shfl.sync, lane by lane in order.
inline int Persistent_TakeTogether(global int* next, uint wanting) {
    uint lane, below;
    __asm__ volatile("mov.u32 %0, %%laneid;" : "=r"(lane));
    __asm__ volatile("mov.u32 %0, %%lanemask_lt;" : "=r"(below));
    const uint leader = (uint)(31 - clz(wanting & -wanting));
    int base = 0;
    if (lane == leader) base = atomic_add(next, (int)popcount(wanting));
    __asm__ volatile("shfl.sync.idx.b32 %0, %1, %2, 0x1f, %3;"
                     : "=r"(base)
                     : "r"(base), "r"(leader), "r"(wanting));
    return base + (int)popcount(wanting & below);
}
#else
// Elsewhere each work-item is a warp of its own: it takes a pixel as soon as it has none.
inline bool Persistent_Refill(bool idle, uint* wanting) {
    *wanting = idle ? 1u : 0u;
    return true;
}
inline int Persistent_TakeTogether(global int* next, uint wanting) { return atomic_inc(next); }
#endif

// The phase clocks (RT_PERSIST_PHASE_CLOCKS, a diagnostic; the counting frame only, on NVIDIA):
// at each mark the warp's lanes meet (bar.warp.sync) and its first lane adds the cycles since the
// last mark to phase `slot` (RT_PHASE_*, persistent/phases.h), in units of 64. The meetings are the
// clocks' own: read the phases' shares, not their cycles (scripts/charts_phases.py). Without
// the clocks a PhaseClock is a placeholder and PHASE_MARK compiles to nothing.
#if defined(RT_PERSIST_PHASE_CLOCKS) && defined(RT_WARP_PTX) && defined(RT_COUNT_RAYS) && \
    defined(RT_COUNT_LANES)
#define PHASE_CLOCKS 1
typedef struct PhaseClock {
    ulong t;     // the cycle count at the last mark
    uint warp;   // the caller's warp's lanes
    bool first;  // the caller is its warp's first lane
} PhaseClock;

inline ulong Phase_Now(void) {
    ulong c;
    __asm__ volatile("mov.u64 %0, %%clock64;" : "=l"(c));
    return c;
}

// Starts the clock of a lane of a one-dimensional work-group of `lanes` lanes.
inline PhaseClock Phase_Start(int lane, int lanes) {
    PhaseClock c;
    const int warpLanes = min(32, lanes - (lane & ~31));
    c.warp = warpLanes == 32 ? 0xffffffffu : (1u << warpLanes) - 1u;
    c.first = (lane & 31) == 0;
    c.t = Phase_Now();
    return c;
}

inline void Phase_Mark(const SceneData* sc, int slot, PhaseClock* c) {
    __asm__ volatile("bar.warp.sync %0;" ::"r"(c->warp));
    const ulong now = Phase_Now();
    if (c->first) atomic_add(&sc->rayCounts[RT_COUNT_PHASES + slot], (uint)((now - c->t) >> 6));
    c->t = now;
}
#define PHASE_MARK(sc, slot, clock) Phase_Mark(sc, slot, clock)
#else
typedef int PhaseClock;
inline PhaseClock Phase_Start(int lane, int lanes) { return 0; }
#define PHASE_MARK(sc, slot, clock) ((void)(clock))
#endif

// A lane's pixel: which one (-1: none), its AA sample, the current sample's sum and the sum of
// its finished samples. The stack of pending rays and its top stay apart, in private arrays.
typedef struct PersistentLane {
    int pixel, sample;
    int2 xy;
    float3 color, acc;
} PersistentLane;

// Starts the lane on pixel k of the launch's pixels: its first sample's primary ray.
inline void Persistent_Begin(const SceneData* sc, PersistentLane* l, RT_STACK_RECORD* stack,
                             int* top, int k, int first, int count) {
    l->xy = Persistent_PixelOf(k, first, count, sc->settings.width);
    l->pixel = l->xy.y * sc->settings.width + l->xy.x;
    l->sample = 0;
    stack[(*top)++] = RT_STACK_PUSH(PathState_Primary(sc, l->xy.x, l->xy.y, 0));
    l->color = (float3)(0.0f, 0.0f, 0.0f);
}

// Once the current sample's tree is done: adds the sample to the pixel's sum and starts the
// next sample, or stores the pixel's mean and frees the lane.
inline void Persistent_EndOfTree(const SceneData* sc, global float* image, PersistentLane* l,
                                 RT_STACK_RECORD* stack, int* top, int samples) {
    if (*top != 0 || l->pixel < 0) return;
    l->acc = l->sample == 0 ? l->color : l->acc + l->color;
    if (++l->sample == samples) {
        Megakernel_Store(image, l->pixel * 3, l->acc / (float)samples);
        l->pixel = -1;
    } else {
        stack[(*top)++] = RT_STACK_PUSH(PathState_Primary(sc, l->xy.x, l->xy.y, l->sample));
        l->color = (float3)(0.0f, 0.0f, 0.0f);
    }
}

// What the regrouped and the staged bounce loops sort hits by: the procedural pattern. (Keying
// hits without a pattern by material class too was 1-3% slower everywhere; persistent/README.md.)
// The key numbering (RT_KEY_*, with mirror and glass between the patterns and a miss) is
// auto/handout_order.h's, which the predictor shares; the key count sizes the local arrays.
#define RG_MISS RT_KEY_MISS  // auto/handout_order.h, shared with the predictor
#define RG_IDLE RT_KEY_IDLE
#define RG_KEYS RT_KEYS

// The sort key of a traced ray's hit.
inline int Regroup_KeyOf(const SceneData* sc, const Node* node) {
    if (node->kind == RT_KIND_MISS) return RG_MISS;
    const global Material* m = &sc->materials[node->material];
    return m->pattern;
}
#endif  // RT_PERSIST_HANDOUT_CL
