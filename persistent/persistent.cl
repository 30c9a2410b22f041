// rtlab — the persistent megakernel (Aila and Laine 2009's persistent threads): as many
// work-items as the device keeps busy at once, each taking its next pixel from a global counter
// once its own pixel is done.
//
// The loop is flat: one iteration traces one ray of whatever pixel the lane holds, and a lane
// whose stack runs dry takes its next pixel at the top of an iteration. A loop over pixels with a
// loop over rays inside it would gain nothing on a SIMT machine: the lanes that leave the inner
// loop wait at its end for the warp's deepest ray tree, exactly as in the one-pixel megakernel.
//
// Pixels are handed out in strips (Persistent_PixelOf, --persistent-tile), so that lanes taking
// pixels at the same time get neighbours, whose rays take the same paths through the scene, and
// a warp's next pixels lie below its last ones. On NVIDIA (RT_WARP_PTX) the lanes of a warp without
// a pixel take consecutive pixels with one atomic add, once `refill` of them are idle (or none is
// busy): waiting for more trades idle steps for lanes that start together. The host's default, 1,
// takes at once: on walls of small objects with mirrors and glass, waiting cost more than the
// coherence it bought.
//
// The per-ray work is the weighted megakernel's (Megakernel_TraceNext), and each pixel's rays and
// samples are summed in the same order, so the image is the same to the bit.
//
// The other forms, each chosen at build time (--persistent-loop, --persistent-regroup): the bounce
// loop (RT_PERSIST_BOUNCE, a work-group's batch of pixels traced bounce by bounce), the nested
// loop (RT_PERSIST_NESTED), the lockstep loop (RT_PERSIST_LOCKSTEP) and the regrouped flat loop
// (RT_PERSIST_REGROUP), in that order below.
#include "megakernel_sample.cl"

// Pixel `k` of the `count` pixels from `first` in row-major order. Whole rows go by strips of
// RT_PERSIST_TILE_W columns and RT_PERSIST_TILE_H rows, row by row inside a strip (bands of TILE_H
// rows, the last band and the last strip of a band cut to fit); anything else (part of one row,
// under --max-launch-ms) goes left to right.
inline int2 Persistent_PixelOf(int k, int first, int count, int width) {
    if (first % width != 0 || count % width != 0) {
        const int p = first + k, y = p / width;
        return (int2)(p - y * width, y);
    }
    const int tw = RT_PERSIST_TILE_W, th = RT_PERSIST_TILE_H;
    const int rows = count / width, band = k / (width * th);
    const int bandRows = min(th, rows - band * th), i = k - band * width * th;
    const int strip = i / (tw * bandRows), j = i - strip * tw * bandRows;
    const int stripWidth = min(tw, width - strip * tw);
    return (int2)(strip * tw + j % stripWidth, first / width + band * th + j / stripWidth);
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
// Whether the warp's lanes without a pixel take new ones this step: once `refill` of its lanes
// are idle, or all of them. Every lane calls it; *wanting gets the idle lanes (PTX
// vote.sync.ballot among the lanes that run it together).
inline bool Persistent_Refill(bool idle, int refill, uint* wanting) {
    uint active, idleLanes;
    __asm__ volatile("activemask.b32 %0;" : "=r"(active));
    __asm__ volatile("{ .reg .pred q; setp.ne.u32 q, %1, 0; vote.sync.ballot.b32 %0, q, %2; }"
                     : "=r"(idleLanes)
                     : "r"((uint)idle), "r"(active));
    *wanting = idleLanes;
    return (int)popcount(idleLanes) >= refill || idleLanes == active;
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
inline bool Persistent_Refill(bool idle, int refill, uint* wanting) {
    *wanting = idle ? 1u : 0u;
    return true;
}
inline int Persistent_TakeTogether(global int* next, uint wanting) { return atomic_inc(next); }
#endif

// The phase clocks (RT_PERSIST_PHASE_CLOCKS, a diagnostic; the counting frame only, on NVIDIA):
// at each mark the warp's lanes meet (bar.warp.sync) and its first lane adds the cycles since the
// last mark to phase `slot` (RT_PHASE_*, core/types.h), in units of 64. The meetings are the
// clocks' own: read the phases' shares, not their cycles (tools/rtlab_report/charts_phases.py).
// Without the clocks a PhaseClock is a placeholder and PHASE_MARK compiles to nothing.
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

// What the regrouped and the sorted bounce loops sort hits by (--persistent-regroup): the
// procedural pattern; with RT_PERSIST_REGROUP_CLASS, a hit without one is keyed by its material
// class too (plain, mirror, glass), as the queue wavefront's shade queues are.
#define RG_MIRROR (RT_PATTERN_BUMP + 1)  // no pattern, reflective
#define RG_GLASS (RG_MIRROR + 1)         // no pattern, transparent
#define RG_MISS (RG_GLASS + 1)           // a ray that left the scene
#define RG_IDLE (RG_MISS + 1)            // a lane without a ray this step
#define RG_KEYS (RG_IDLE + 1)

// The sort key of a traced ray's hit.
inline int Regroup_KeyOf(const SceneData* sc, const Node* node) {
    if (node->kind == RT_KIND_MISS) return RG_MISS;
    const global Material* m = &sc->materials[node->material];
#ifdef RT_PERSIST_REGROUP_CLASS
    if (m->pattern == RT_PATTERN_NONE) {
        if (m->opacity < 1.0f) return RG_GLASS;
        if (m->reflectance > 0.0f) return RG_MIRROR;
    }
#endif
    return m->pattern;
}

#if defined(RT_PERSIST_BOUNCE)
// The bounce form (--persistent-loop bounce; RT_PERSIST_BOUNCE is the work-group size): a
// wavefront inside the persistent launch. A work-group takes a batch of `batch` pixels from the
// counter and traces their rays bounce by bounce: all camera rays, then all their children, and so
// on, each bounce's rays in one list in global memory (BounceRay, core/types.h). A warp takes 32
// consecutive rays of the list and appends their children together, so that a warp traces rays
// of one bounce from neighbouring pixels, the order the queue wavefront's extend kernel traces
// them in. The other loops trace a lane's own pixel's rays, and a warp's lanes part at the first
// mirror. No lane keeps a stack of pending rays, only the ray it traces.
//
// Each ray's term and children go to its pixel's tree (BounceTerm at the ray's slot), and once the
// batch's trees are done each pixel sums its terms in the weighted megakernel's order: depth
// first, the reflection's subtree before the refraction's (Bounce_Sum). Same terms, computed by the
// same code from the same bits, added in the same order: the weighted megakernel's image to the
// bit, whatever order the lists come in. The AA samples of a batch go one after another, summed
// in the image buffer.
//
// Scratch (the host sizes it, setBounceScratch): per work-group two lists of `widest` rays (batch
// * C^B, the widest bounce a batch can have) and batch * N terms (N slots of a tree of B bounces,
// RayTree_NodeCount).

inline BounceRay Bounce_Pack(const Pending* p, int pixel, int slot) {
    BounceRay r;
    r.origin = F3(p->ray.origin);
    r.dir = F3(p->ray.dir);
    r.weight = F3(p->weight);
    r.depthType = p->depth << 8 | p->type;
    r.pixel = pixel;
    r.slot = slot;
    return r;
}

inline Pending Bounce_Unpack(BounceRay r) {
    return PathState_Make(makeRay(f3(r.origin), f3(r.dir)), f3(r.weight), r.depthType >> 8,
                          r.depthType & 0xff);
}

// A pixel's colour from its tree of terms (slot 0 its camera ray), summed in pre-order with the
// reflection first: the order in which the weighted megakernel's stack pops the same rays.
inline float3 Bounce_Sum(const global BounceTerm* tree) {
    float3 color = (float3)(0.0f, 0.0f, 0.0f);
    int i = 0;
    for (;;) {
        color += f3(tree[i].term);
        const int children = tree[i].children;
        if (children != 0) {  // down to the first child
            i = i * RT_BRANCH + ((children & 1) ? 1 : 2);
            continue;
        }
        // Up to the nearest ancestor entered by its reflection that also has a refraction.
        for (;;) {
            if (i == 0) return color;
            const int parent = (i - 1) / RT_BRANCH;
            if (i == parent * RT_BRANCH + 1 && (tree[parent].children & 2)) {
                i = parent * RT_BRANCH + 2;
                break;
            }
            i = parent;
        }
    }
}

// A warp's share of a bounce, on NVIDIA (RT_WARP_PTX): its lanes take the next 32 rays of the
// bounce together and append their children together, one local atomic each, the children lane
// by lane in order, so that the next bounce's warps again trace neighbours' rays. Elsewhere a
// work-item is a warp of its own. No work-group barrier inside a bounce: a warp that is done
// takes more rays instead of waiting for the group's slowest.
typedef struct BounceWarp {
    uint lanes;  // the warp's lanes (mask)
    int count;   // how many
    int lane;    // the caller's, within the warp
} BounceWarp;

inline BounceWarp Bounce_WarpOf(int lane) {
    BounceWarp w;
#ifdef RT_WARP_PTX
    // A one-dimensional work-group fills its warps 32 work-items at a time; only its last warp
    // may have fewer.
    w.count = min(32, RT_PERSIST_BOUNCE - (lane & ~31));
    w.lanes = w.count == 32 ? 0xffffffffu : (1u << w.count) - 1u;
    w.lane = lane & 31;
#else
    w.lanes = 1u;
    w.count = 1;
    w.lane = 0;
#endif
    return w;
}

// The first of the warp's next w->count rays of the bounce; every lane of the warp calls it.
inline int Bounce_Take(local int* taken, const BounceWarp* w) {
#ifdef RT_WARP_PTX
    int base = 0;
    if (w->lane == 0) base = atomic_add(taken, w->count);
    return Persistent_WarpShuffle(base, 0, w->lanes);
#else
    return atomic_inc(taken);
#endif
}

// Where the caller's children (bit 0 reflection, bit 1 refraction, in that order) go in the next
// bounce's list; every lane of the warp calls it.
inline int Bounce_Place(local int* produced, int children, const BounceWarp* w) {
#ifdef RT_WARP_PTX
    const uint refl = Persistent_WarpBallot((children & 1) != 0, w->lanes);
    const uint refr = Persistent_WarpBallot((children & 2) != 0, w->lanes);
    uint below;
    __asm__ volatile("mov.u32 %0, %%lanemask_lt;" : "=r"(below));
    int base = 0;
    if (w->lane == 0) base = atomic_add(produced, (int)(popcount(refl) + popcount(refr)));
    base = Persistent_WarpShuffle(base, 0, w->lanes);
    return base + (int)(popcount(refl & below) + popcount(refr & below));
#else
    return atomic_add(produced, (int)popcount(children));
#endif
}

// Shades a traced ray of pixel `pixel`'s tree slot `slot`: its term and children into the tree,
// the children appended to `out`. Every lane of the warp calls it, `has` false where the lane has
// no ray.
inline void Bounce_Shade(const SceneData* sc, bool has, const Node* node, const Pending* p,
                         int pixel, int slot, global BounceTerm* tree, global BounceRay* out,
                         local int* produced, const BounceWarp* w) {
    int children = 0;
    Pending refl, refr;
    if (has) {
        float3 term;
        if (node->kind == RT_KIND_MISS) {
            term = PathState_Miss(sc, p);
        } else {
            bool hasRefl, hasRefr;
            term = PathState_Step(sc, node, p, true, true, RT_PATTERN_ANY, &refl, &hasRefl, &refr,
                                  &hasRefr);
            children = (hasRefl ? 1 : 0) | (hasRefr ? 2 : 0);
        }
        tree[slot].term = F3(term);
        tree[slot].children = children;
    }
    int o = Bounce_Place(produced, children, w);
    if (children & 1) out[o++] = Bounce_Pack(&refl, pixel, slot * RT_BRANCH + 1);
    if (children & 2) out[o] = Bounce_Pack(&refr, pixel, slot * RT_BRANCH + 2);
}

// Staged: a bounce's traced rays wait in `hits` between passes over them, with `order` a list of
// their indices.
//   Sorted (--persistent-regroup with the bounce loop): the group counts the hits by key and
//   shades them in key order, so that a warp runs one pattern's code at a time. Only mirrors and
//   glass spawn children, and the ranks within a key follow the trace, so the next bounce's rays
//   stay close to the order of their pixels.
//   Shadow pass (--persistent-shadows pass): the trace finds the closest hits only, and a pass of
//   its own casts the shadow rays of the hits (not the misses) in trace order, as the queue's
//   shadow kernel does, so that a warp's lanes cast shadow rays together rather than each after
//   its own trace.
#if defined(RT_PERSIST_BOUNCE_SORT) || defined(RT_PERSIST_BOUNCE_SHADOW_PASS)
#define BOUNCE_STAGED
#define BOUNCE_STAGED_PARAMS , global BounceHit *hits, global int *order
#else
#define BOUNCE_STAGED_PARAMS
#endif

// A work-group's counters of one bounce, in local memory; Bounce_Reset zeroes them between
// bounces.
typedef struct BounceCounters {
    int taken;                                // rays taken for the trace by the group's warps
    int produced;                             // children appended to the next bounce's list
    int casting;                              // hits listed for the shadow pass
    int cast;                                 // of those, taken for the shadow pass
    int shaded;                               // staged hits taken for shading
    int keyCount[RG_KEYS], keyBase[RG_KEYS];  // the sorted loop's hits by key
} BounceCounters;

inline void Bounce_Reset(local BounceCounters* c, int lane) {
    if (lane == 0) c->taken = c->produced = c->casting = c->cast = c->shaded = 0;
    if (lane < RG_KEYS) c->keyCount[lane] = 0;
}

// What a bounce's passes share: the caller's warp, the group's counters and scratch, and which
// pixels and AA sample the batch is at.
typedef struct Bounce {
    BounceWarp warp;
    local BounceCounters* c;
    global BounceTerm* trees;  // batch x slots
    global BounceHit* hits;    // staged: one a ray of the bounce
    global int* order;         // staged: hit indices, for the shadow pass and the sorted shading
    int start, first, count, sample, slots;
    PhaseClock* phases;  // the caller's phase clock (RT_PERSIST_PHASE_CLOCKS)
} Bounce;

// The trace: every ray of `in` (the batch's camera rays at depth 0) to its closest hit, with its
// shadow rays unless a pass of their own casts them. Unstaged, each hit is shaded at once and its
// children appended to `out`; staged, it waits in b->hits.
inline void Bounce_TracePass(const SceneData* sc, const Bounce* b, int depth, int n,
                             global const BounceRay* in, global BounceRay* out) {
    for (;;) {
        const int base = Bounce_Take(&b->c->taken, &b->warp);
        if (base >= n) return;  // the same for the whole warp
        const int i = base + b->warp.lane;
        Pending p;
        int pixel = 0, slot = 0;
        Node node;
        if (i < n) {
            if (depth == 0) {
                pixel = i;
            } else {
                const BounceRay r = in[i];
                pixel = r.pixel;
                slot = r.slot;
                p = Bounce_Unpack(r);
            }
            const int2 xy =
                Persistent_PixelOf(b->start + pixel, b->first, b->count, sc->settings.width);
            if (depth == 0) p = PathState_Primary(sc, xy.x, xy.y, b->sample);
            RT_COUNT_WARP_STEP(sc);  // the lanes that trace a ray this take
#ifdef RT_PERSIST_BOUNCE_SHADOW_PASS
            node = RayTree_TraceSurface(sc, p.ray, p.type);
#else
            node = RayTree_TraceNode(sc, p.ray, p.type,
                                     Sampling_PointKey(xy.x, xy.y, b->sample, p.depth));
#endif
        }
        PHASE_MARK(sc, RT_PHASE_TRACE, b->phases);
#ifdef BOUNCE_STAGED
        if (i < n) {
            global BounceHit* h = &b->hits[i];
            h->node = node;
            h->ray = Bounce_Pack(&p, pixel, slot);
#ifdef RT_PERSIST_BOUNCE_SORT
            const int key = Regroup_KeyOf(sc, &node);
            h->key = key;
            h->rank = atomic_inc(&b->c->keyCount[key]);
#endif
        }
#ifdef RT_PERSIST_BOUNCE_SHADOW_PASS
        const bool casts = i < n && node.kind != RT_KIND_MISS && sc->settings.lightCount > 0;
        const int at = Bounce_Place(&b->c->casting, casts ? 1 : 0, &b->warp);
        if (casts) b->order[at] = i;
#endif
        PHASE_MARK(sc, RT_PHASE_FILE, b->phases);
#else
        Bounce_Shade(sc, i < n, &node, &p, pixel, slot, &b->trees[(size_t)pixel * b->slots], out,
                     &b->c->produced, &b->warp);
        PHASE_MARK(sc, RT_PHASE_SHADE, b->phases);
#endif
    }
}

// The shadow pass: the shadow rays of the hits the trace listed, with the key the trace would have
// given them (their pixel, AA sample and depth).
inline void Bounce_ShadowPass(const SceneData* sc, const Bounce* b) {
    const int casting = b->c->casting;
    for (;;) {
        const int base = Bounce_Take(&b->c->cast, &b->warp);
        if (base >= casting) return;
        const int j = base + b->warp.lane;
        if (j < casting) {
            global BounceHit* h = &b->hits[b->order[j]];
            Node node = h->node;
            const int2 xy =
                Persistent_PixelOf(b->start + h->ray.pixel, b->first, b->count, sc->settings.width);
            RayTree_CastShadows(sc, &node,
                                Sampling_PointKey(xy.x, xy.y, b->sample, h->ray.depthType >> 8));
            for (int l = 0; l < sc->settings.lightCount; ++l)
                h->node.occluded[l] = node.occluded[l];
        }
        PHASE_MARK(sc, RT_PHASE_SHADOW, b->phases);
    }
}

// The sorted loop's order: each key's first place, then every hit's place, into b->order.
// Every lane of the group calls it.
inline void Bounce_SortPass(const Bounce* b, int n, int lane) {
    if (lane == 0)
        for (int k = 0, at = 0; k < RG_KEYS; ++k) {
            b->c->keyBase[k] = at;
            at += b->c->keyCount[k];
        }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int i = lane; i < n; i += RT_PERSIST_BOUNCE)
        b->order[b->c->keyBase[b->hits[i].key] + b->hits[i].rank] = i;
}

// Shading the staged hits, in key order when sorted, in trace order otherwise; their children
// appended to `out`.
inline void Bounce_ShadePass(const SceneData* sc, const Bounce* b, int n, global BounceRay* out) {
    for (;;) {
        const int base = Bounce_Take(&b->c->shaded, &b->warp);
        if (base >= n) return;
        const int k = base + b->warp.lane;
        BounceHit h;
        h.ray.pixel = h.ray.slot = 0;
        Pending p;
        if (k < n) {
#ifdef RT_PERSIST_BOUNCE_SORT
            h = b->hits[b->order[k]];
#else
            h = b->hits[k];
#endif
            p = Bounce_Unpack(h.ray);
        }
        Bounce_Shade(sc, k < n, &h.node, &p, h.ray.pixel, h.ray.slot,
                     &b->trees[(size_t)h.ray.pixel * b->slots], out, &b->c->produced, &b->warp);
        PHASE_MARK(sc, RT_PHASE_SHADE, b->phases);
    }
}

kernel RT_GROUP_LANES(RT_PERSIST_BOUNCE) void Persistent_RenderBounce(
    RT_SCENE_PARAMS, global float* image, global int* next, int first, int count,
    global BounceRay* rays, global BounceTerm* terms, int batch, int widest BOUNCE_STAGED_PARAMS) {
    RT_SCENE_INIT(sc);
    local int start;  // the group's first pixel this batch
    local BounceCounters counters;
    const int lane = (int)get_local_id(0);
    const int samples = settings.aaSamples * settings.aaSamples;
    const size_t group = get_group_id(0);
    global BounceRay* lists = rays + group * 2 * (size_t)widest;
    Bounce b;
    b.warp = Bounce_WarpOf(lane);
    b.c = &counters;
    b.slots = RayTree_NodeCount(settings.bounces);
    b.trees = terms + group * (size_t)batch * (size_t)b.slots;
#ifdef BOUNCE_STAGED
    b.hits = hits + group * (size_t)widest;
    b.order = order + group * (size_t)widest;
#else
    b.hits = 0;
    b.order = 0;
#endif
    b.first = first;
    b.count = count;
    PhaseClock phases = Phase_Start(lane, RT_PERSIST_BOUNCE);
    b.phases = &phases;
    Bounce_Reset(&counters, lane);
    for (;;) {
        barrier(CLK_LOCAL_MEM_FENCE);  // every lane has read the last batch's start
        if (lane == 0) start = atomic_add(next, batch);
        barrier(CLK_LOCAL_MEM_FENCE);
        if (start >= count) break;  // the whole group leaves together
        b.start = start;
        const int pixels = min(batch, count - start);
        for (b.sample = 0; b.sample < samples; ++b.sample) {
            global BounceRay* in = lists;
            global BounceRay* out = lists + widest;
            // One bounce at a time: rays [0, n) of `in` (the camera rays at depth 0), their
            // children appended to `out`. The group meets after each pass, whose successor reads
            // what other lanes wrote in it.
            for (int depth = 0, n = pixels; n > 0; ++depth) {
                PHASE_MARK(&sc, RT_PHASE_BOOKKEEPING, &phases);
                Bounce_TracePass(&sc, &b, depth, n, in, out);
                barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
                PHASE_MARK(&sc, RT_PHASE_TRACE_WAIT, &phases);
#ifdef RT_PERSIST_BOUNCE_SHADOW_PASS
                Bounce_ShadowPass(&sc, &b);
                barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
                PHASE_MARK(&sc, RT_PHASE_SHADOW_WAIT, &phases);
#endif
#ifdef RT_PERSIST_BOUNCE_SORT
                Bounce_SortPass(&b, n, lane);
                barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
                PHASE_MARK(&sc, RT_PHASE_FILE, &phases);
#endif
#ifdef BOUNCE_STAGED
                Bounce_ShadePass(&sc, &b, n, out);
                barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
                PHASE_MARK(&sc, RT_PHASE_SHADE_WAIT, &phases);
#endif
                n = counters.produced;
                barrier(CLK_LOCAL_MEM_FENCE);  // every lane has read the count
                Bounce_Reset(&counters, lane);
                barrier(CLK_LOCAL_MEM_FENCE);
                global BounceRay* swap = in;
                in = out;
                out = swap;
            }
            // The batch's trees are traced: each pixel's sum, added to its earlier samples'.
            for (int pixel = lane; pixel < pixels; pixel += RT_PERSIST_BOUNCE) {
                const int2 xy = Persistent_PixelOf(start + pixel, first, count, settings.width);
                const int at = (xy.y * settings.width + xy.x) * 3;
                float3 c = Bounce_Sum(&b.trees[(size_t)pixel * b.slots]);
                if (b.sample > 0) c += (float3)(image[at], image[at + 1], image[at + 2]);
                if (b.sample == samples - 1) c = c / (float)samples;
                Megakernel_Store(image, at, c);
            }
            barrier(CLK_GLOBAL_MEM_FENCE);  // the next sample rewrites trees other lanes summed
            PHASE_MARK(&sc, RT_PHASE_BOOKKEEPING, &phases);
        }
    }
}
#elif defined(RT_PERSIST_NESTED)
// The nested form (--persistent-loop nested): Aila and Laine's own shape, a loop over pixels
// around the one-pixel megakernel's loop over rays. The work-group takes a pixel for each of its
// lanes with one atomic add, each lane renders its pixel as Megakernel_Render does, and the group
// takes the next ones once all of its lanes are done: the megakernel's own work-groups, dealt by
// a counter to a launch that fills the device once. Taken a work-group at a time, a compute
// unit's warps work on one patch of the frame, whose rays share the caches, instead of on patches
// taken a warp at a time as the warps come free. Against the flat loop it has no per-ray vote or
// refill test, and its lanes wait for the group's deepest tree. Same pixels, same sums, same bits.
// `refill` is the flat loop's; it is unused here.
kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count, int refill) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    const int lane = (int)get_local_id(0);
    local int base;  // the group's first pixel this round
    for (;;) {
        barrier(CLK_LOCAL_MEM_FENCE);  // every lane has read the last round's base
        if (lane == 0) base = atomic_add(next, (int)get_local_size(0));
        barrier(CLK_LOCAL_MEM_FENCE);
        if (base >= count) break;  // the whole group leaves together: every lane meets each barrier
        const int k = base + lane;
        if (k < count) {
            const int2 xy = Persistent_PixelOf(k, first, count, settings.width);
            Megakernel_Store(image, (xy.y * settings.width + xy.x) * 3,
                             Megakernel_PixelMean(&sc, xy.x, xy.y, samples));
        }
    }
}
#elif defined(RT_PERSIST_LOCKSTEP) && defined(RT_WARP_PTX)
// The lockstep form (--persistent-loop lockstep, NVIDIA): the flat loop below, with the warp's 32
// lanes starting every step together. In the flat loop a warp's lanes part ways inside a step
// (a mirror's lane in its reflection code, a plain one in its pattern's) and need not meet again
// at the top, so the lanes that trace together are fewer than the lanes holding rays. Here two
// votes of the whole warp (vote.sync naming every lane, which waits for all of them) open each
// step: the idle lanes take consecutive pixels, then every lane holding a ray traces it. The
// regrouped form gets its full steps from work-group barriers and local memory; this one needs
// neither, and does not sort the shading. The votes name the warp's lanes (all 32, or fewer in the
// last warp of a work-group of 16 or 48 lanes), and no lane leaves before the warp does, as
// vote.sync requires. Same pixels, same sums, same bits; `refill` does not apply (the host
// refuses it).

kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count, int refill) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0;
    PersistentLane l;
    l.pixel = -1;
    bool drained = false;  // the counter has no pixel left for this lane
    // The warp's lanes: a one-dimensional work-group fills its warps 32 work-items at a time, so
    // only its last warp may have fewer.
    const int warpFirst = (int)get_local_id(0) & ~31;
    const int warpLanes = min(32, (int)get_local_size(0) - warpFirst);
    const uint warp = warpLanes == 32 ? 0xffffffffu : (1u << warpLanes) - 1u;
    for (;;) {
        Persistent_EndOfTree(&sc, image, &l, stack, &top, samples);
        const bool wants = l.pixel < 0 && !drained;
        const uint wanting = Persistent_WarpBallot(wants, warp);
        if (wants) {
            const int k = Persistent_TakeTogether(next, wanting);
            if (k >= count)
                drained = true;
            else
                Persistent_Begin(&sc, &l, stack, &top, k, first, count);
        }
        if (Persistent_WarpBallot(l.pixel >= 0, warp) == 0u) return;  // the warp leaves together
        if (l.pixel >= 0) {
            RT_COUNT_WARP_STEP(&sc);  // the lanes that trace a ray this step
            l.color += Megakernel_TraceNext(&sc, stack, &top, l.xy.x, l.xy.y, l.sample);
        }
    }
}
#elif !defined(RT_PERSIST_REGROUP)
// Pixels [first, first + count) of the frame; *next counts the ones taken (zeroed by the host
// before each launch). `refill`: RT_WARP_PTX only, the idle lanes a warp waits for. Also the
// lockstep form's, elsewhere than on NVIDIA: there each work-item is a warp of its own.
kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count, int refill) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0;
    PersistentLane l;
    l.pixel = -1;
    for (;;) {
        Persistent_EndOfTree(&sc, image, &l, stack, &top, samples);
        uint wanting;
        const bool refillNow = Persistent_Refill(l.pixel < 0, refill, &wanting);
        if (l.pixel < 0 && refillNow) {
            const int k = Persistent_TakeTogether(next, wanting);
            if (k >= count) return;
            Persistent_Begin(&sc, &l, stack, &top, k, first, count);
        }
        if (l.pixel < 0) continue;  // waiting for the warp's refill
        RT_COUNT_WARP_STEP(&sc);    // the lanes that trace a ray this step
        l.color += Megakernel_TraceNext(&sc, stack, &top, l.xy.x, l.xy.y, l.sample);
    }
}
#else
// The regrouped form (--persistent-regroup pattern or material; RT_PERSIST_REGROUP is the
// work-group size): the loop above, with each step cut in two at the hit. Every lane traces its
// own ray; then the work-group sorts the hits by what shades them in local memory (a miss and an
// idle lane are two more keys), and lane i shades the i-th hit of that order, whoever's it is,
// so that the lanes of a warp run one shading path together instead of one after the other (a
// software form of shader execution reordering). The owner takes back the result and sums and
// pushes it exactly as Megakernel_TraceNext does: a pixel's terms arrive in the same order and
// each is computed by the same code from the same bits, so the image stays the weighted
// megakernel's. Each lane takes a pixel as soon as it has none (`refill` does not apply).
#define RG_LANES RT_PERSIST_REGROUP

// A lane's slot in local memory holds a hit to shade, then what shading it gave: lane i copies
// slot i's hit into registers before it writes slot i's result, and no other lane touches slot i
// between the two barriers, so one array serves both. kRegroupSlotBytes (persistent.cpp) is the
// size of this union.
typedef struct RegroupHit {
    Node node;
    Pending p;
} RegroupHit;

typedef struct RegroupShade {
    float3 term;
    Pending refl, refr;
    int children;  // bit 0: refl, bit 1: refr
} RegroupShade;

typedef union RegroupSlot {
    RegroupHit hit;
    RegroupShade shade;
} RegroupSlot;

// Shades one traced ray: its term and the children it spawns.
inline RegroupShade Regroup_Shade(const SceneData* sc, const Node* n, const Pending* q) {
    RegroupShade s;
    s.children = 0;
    if (n->kind == RT_KIND_MISS) {
        s.term = PathState_Miss(sc, q);
    } else {
        bool hasRefl, hasRefr;
        s.term = PathState_Step(sc, n, q, true, true, RT_PATTERN_ANY, &s.refl, &hasRefl, &s.refr,
                                &hasRefr);
        s.children = (hasRefl ? 1 : 0) | (hasRefr ? 2 : 0);
    }
    return s;
}

kernel RT_GROUP_LANES(RG_LANES) void Persistent_RenderRegrouped(RT_SCENE_PARAMS,
                                                                global float* image,
                                                                global int* next, int first,
                                                                int count, int refill) {
    RT_SCENE_INIT(sc);
    local RegroupSlot slots[RG_LANES];
    // Key counts, three sets in turn, so that a step needs no barrier before it counts: it
    // zeroes the next step's set, last read two steps back, which every lane has left once it
    // passed the last step's barriers.
    local int keys[3][RG_KEYS];
    const int lane = (int)get_local_id(0);
    const int samples = settings.aaSamples * settings.aaSamples;
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0;
    PersistentLane l;
    l.pixel = -1;
    bool drained = false;  // the counter has no pixel left for this lane
    if (lane < RG_KEYS) keys[0][lane] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    PhaseClock phases = Phase_Start(lane, RG_LANES);
    for (int step = 0;; step = step == 2 ? 0 : step + 1) {
        Persistent_EndOfTree(&sc, image, &l, stack, &top, samples);
        if (l.pixel < 0 && !drained) {
            const int k = atomic_inc(next);
            if (k >= count)
                drained = true;
            else
                Persistent_Begin(&sc, &l, stack, &top, k, first, count);
        }
        PHASE_MARK(&sc, RT_PHASE_BOOKKEEPING, &phases);
        local int* counts = keys[step];
        if (lane < RG_KEYS) keys[step == 2 ? 0 : step + 1][lane] = 0;

        // Trace this lane's ray and count its hit under its key.
        Pending p;
        Node node;
        int key = RG_IDLE;
        if (l.pixel >= 0) {
            RT_COUNT_WARP_STEP(&sc);  // the lanes that trace a ray this step
            p = RT_STACK_POP(stack[--top]);
            node = RayTree_TraceNode(&sc, p.ray, p.type,
                                     Sampling_PointKey(l.xy.x, l.xy.y, l.sample, p.depth));
            key = Regroup_KeyOf(&sc, &node);
        }
        const int rank = atomic_inc(&counts[key]);
        PHASE_MARK(&sc, RT_PHASE_TRACE, &phases);
        barrier(CLK_LOCAL_MEM_FENCE);
        PHASE_MARK(&sc, RT_PHASE_TRACE_WAIT, &phases);
        // The whole work-group leaves together, once none of its lanes holds a ray: every lane
        // must reach every barrier.
        if (counts[RG_IDLE] == RG_LANES) break;

        // File the hit at its place in key order.
        int slot = rank, busy = 0;
        for (int k = 0; k < RG_IDLE; ++k) {
            if (k < key) slot += counts[k];
            busy += counts[k];
        }
        if (l.pixel >= 0) {
            slots[slot].hit.node = node;
            slots[slot].hit.p = p;
        }
        barrier(CLK_LOCAL_MEM_FENCE);
        PHASE_MARK(&sc, RT_PHASE_FILE, &phases);

        // Shade the lane-th hit of that order.
        if (lane < busy) {
            const Node n = slots[lane].hit.node;
            const Pending q = slots[lane].hit.p;
            slots[lane].shade = Regroup_Shade(&sc, &n, &q);
        }
        PHASE_MARK(&sc, RT_PHASE_SHADE, &phases);
        barrier(CLK_LOCAL_MEM_FENCE);
        PHASE_MARK(&sc, RT_PHASE_SHADE_WAIT, &phases);

        // Take back this lane's own result, in Megakernel_TraceNext's order.
        if (l.pixel >= 0) {
            const RegroupShade s = slots[slot].shade;
            l.color += s.term;
            if (s.children & 2) stack[top++] = RT_STACK_PUSH(s.refr);
            if (s.children & 1) stack[top++] = RT_STACK_PUSH(s.refl);
        }
    }
}
#endif
