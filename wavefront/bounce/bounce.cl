// rtlab — the bounce loop (--pipeline persist --persistent-schedule bounce or bounce-staged;
// RT_BOUNCE_LANES is the work-group size): a wavefront inside one persistent launch, filed with
// the wavefronts. A work-group takes a batch of `batch` pixels from the counter and traces their
// rays bounce by bounce: all camera rays, then all their children, and so on, each bounce's rays
// in one list in global memory (BounceRay, bounce_state.h). A warp takes 32 consecutive rays of
// the list and appends their children together, so that a warp traces rays of one bounce from
// neighbouring pixels, the order the queue wavefront's extend kernel traces them in. The
// persistent megakernel's loops trace a lane's own pixel's rays, and a warp's lanes part at the
// first mirror. No lane keeps a stack of pending rays, only the ray it traces.
//
// Each ray's term and children go to its pixel's tree (BounceTerm at the ray's slot), and once the
// batch's trees are done each pixel sums its terms in the weighted megakernel's order: depth
// first, the reflection's subtree before the refraction's (Bounce_Sum). Same terms, computed by the
// same code from the same bits, added in the same order: the weighted megakernel's image to the
// bit, whatever order the lists come in. The AA samples of a batch go one after another, summed
// in the image buffer.
//
// Scratch (the host sizes it, bounce.cpp): per work-group two lists of `widest` rays (batch
// * C^B, the widest bounce a batch can have) and batch * N terms (N slots of a tree of B bounces,
// RayTree_NodeCount). Pixels are handed out as the persistent schedules hand them out.
#include "bounce_state.h"
#include "handout.cl"

RAY_STATE_CODEC(BounceRay)

inline BounceRay Bounce_Pack(const Pending* p, int pixel, int slot) {
    BounceRay r;
    RayState_Pack_BounceRay(p, &r);
    r.pixel = pixel;
    r.slot = slot;
    return r;
}

inline Pending Bounce_Unpack(BounceRay r) { return RayState_Unpack_BounceRay(r); }

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
    w.count = min(32, RT_BOUNCE_LANES - (lane & ~31));
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

// Staged (RT_BOUNCE_STAGED, --persistent-schedule bounce-staged): a bounce's traced rays wait in
// `hits` between passes over them, with `order` a list of their indices.
//   Shadow pass: the trace finds the closest hits only, and a pass of its own casts the shadow
//   rays of the hits (not the misses) in trace order, as the queue's shadow kernel does, so that
//   a warp's lanes cast shadow rays together rather than each after its own trace.
//   Sorted: the group counts the hits by pattern and shades them in key order, so that a warp
//   runs one pattern's code at a time. Only mirrors and glass spawn children, and the ranks
//   within a key follow the trace, so the next bounce's rays stay close to the order of their
//   pixels.
#ifdef RT_BOUNCE_STAGED
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
#ifdef RT_BOUNCE_STAGED
            node = RayTree_TraceSurface(sc, p.ray, p.type);
#else
            node = RayTree_TraceNode(sc, p.ray, p.type,
                                     Sampling_PointKey(xy.x, xy.y, b->sample, p.depth));
#endif
        }
        PHASE_MARK(sc, RT_PHASE_TRACE, b->phases);
#ifdef RT_BOUNCE_STAGED
        if (i < n) {
            global BounceHit* h = &b->hits[i];
            h->node = node;
            h->ray = Bounce_Pack(&p, pixel, slot);
            const int key = Regroup_KeyOf(sc, &node);
            h->key = key;
            h->rank = atomic_inc(&b->c->keyCount[key]);
        }
        const bool casts = i < n && node.kind != RT_KIND_MISS && sc->settings.lightCount > 0;
        const int at = Bounce_Place(&b->c->casting, casts ? 1 : 0, &b->warp);
        if (casts) b->order[at] = i;
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
    for (int i = lane; i < n; i += RT_BOUNCE_LANES)
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
            h = b->hits[b->order[k]];
            p = Bounce_Unpack(h.ray);
        }
        Bounce_Shade(sc, k < n, &h.node, &p, h.ray.pixel, h.ray.slot,
                     &b->trees[(size_t)h.ray.pixel * b->slots], out, &b->c->produced, &b->warp);
        PHASE_MARK(sc, RT_PHASE_SHADE, b->phases);
    }
}

kernel RT_GROUP_LANES(RT_BOUNCE_LANES) void Persistent_RenderBounce(
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
#ifdef RT_BOUNCE_STAGED
    b.hits = hits + group * (size_t)widest;
    b.order = order + group * (size_t)widest;
#else
    b.hits = 0;
    b.order = 0;
#endif
    b.first = first;
    b.count = count;
    PhaseClock phases = Phase_Start(lane, RT_BOUNCE_LANES);
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
#ifdef RT_BOUNCE_STAGED
                Bounce_ShadowPass(&sc, &b);
                barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
                PHASE_MARK(&sc, RT_PHASE_SHADOW_WAIT, &phases);
                Bounce_SortPass(&b, n, lane);
                barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
                PHASE_MARK(&sc, RT_PHASE_FILE, &phases);
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
            for (int pixel = lane; pixel < pixels; pixel += RT_BOUNCE_LANES) {
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
