// rtlab — the queue wavefront: paths live in a pool of ray records in global memory,
// structure of arrays, and every stage is a kernel over a compacted queue of them:
//   generate  -> camera rays into free pool slots (new pixels, or pixels cut for room)
//   extend    -> closest hit of every queued ray; sorts rays into one queue per shading class
//                (--queue-shade: or per pattern, or all hits in one queue for a sort)
//   shadow    -> any-hit shadow rays of every ray that hit a surface
//   shade_*   -> one kernel per queue: the local term, and the children into a staging area
//   scan      -> exclusive prefix sum of the children per ray (stable: order is kept)
//   accumulate-> each path's contributions of this bounce, added to its pixel in queue order
//   compact   -> children from the staging area to the front of the pool, without holes
// A ray carries its pixel and its weight (core/cl/pathstate.cl, the step the megakernel's
// weighted layout takes), so contributions go straight to the pixel: no tree is stored.
//
// Order and determinism: rays of one path sit next to each other in the pool, because generate
// appends whole paths and the prefix sum places every ray's children where its own slot was in
// the order. A path's contributions of one bounce are therefore a contiguous run that one
// work-item sums in a fixed order: the image is the same from run to run, without float atomics.
// The class and shadow queues are filled with atomics and so come in any order, but every result
// is written at the ray's own pool index, so their order changes no pixel.
#include "pathstate.cl"
#include "queue_layout.h"

// --queue-shade (queue_layout.h): the host defines it for the pattern and sort modes only.
#ifndef RT_QUEUE_SHADE
#define RT_QUEUE_SHADE RT_Q_SHADE_CLASS
#endif

// --queue-local-pad N, a diagnostic (RT_Q_LOCAL_PAD=N where N > 0): N bytes of local memory
// that hold nothing, in each work-group of the per-ray stage kernels (extend, shadow, shade),
// so that fewer of their groups are resident on a compute unit at once. The lanes' volatile
// stores keep the compiler from dropping the array; nothing reads it. The first statement of a
// kernel, as local declarations must be at a kernel's scope.
#ifdef RT_Q_LOCAL_PAD
#define QUEUE_LOCAL_PAD()                          \
    local volatile uchar queuePad[RT_Q_LOCAL_PAD]; \
    queuePad[get_local_id(0) % RT_Q_LOCAL_PAD] = 0
#else
#define QUEUE_LOCAL_PAD() (void)0
#endif

// The pool's fields, one array each: the per-ray state (core/ray_state.h, float3 fields as 3
// floats, vload3/vstore3) and the ray's pixel.
typedef struct QueueRays {
    RayStateArrays state;
    global int* pixel;  // y * width + x
} QueueRays;

#define QUEUE_RAYS_PARAMS(p) RAY_STATE_PARAMS(p) global int* p##Pixel
#define QUEUE_RAYS_INIT_F3(p, field, Field, member) p.state.field = p##Field;
#define QUEUE_RAYS_INIT_META(p, field, Field) p.state.field = p##Field;
#define QUEUE_RAYS_INIT(p) \
    QueueRays p;           \
    RT_RAY_STATE(QUEUE_RAYS_INIT_F3, QUEUE_RAYS_INIT_META, p) p.pixel = p##Pixel

// A launch's real length: the host's `n` (readback mode, word < 0), or, when launches are sized
// on the device, the count in counters[word], never past the bound `n` the launch covers.
inline int Queue_Length(int n, int word, global const int* counters) {
    return word < 0 ? n : min(n, counters[word]);
}

inline Pending Queue_Load(const QueueRays* r, int i) { return RayState_Load(&r->state, i); }

inline void Queue_Store(const QueueRays* r, int i, const Pending* p, int pixel) {
    RayState_Store(&r->state, i, p);
    r->pixel[i] = pixel;
}

// Ray counts (RT_COUNT_RAYS): a pixel's rays are counted in its own tally of RT_RAY_TYPES words
// (rayTally + RT_RAY_TYPES (pixel + 1)) while its path of the AA sample runs, not in the frame's
// counters. A path cut for room is traced again from its camera ray, so the rays of the cut
// attempt are the queue's extra work, not the image's: when its pixel starts again, generate
// moves that tally to rayTally[0, RT_RAY_TYPES) (the frame's retraced rays). When a path ends
// (a bounce leaves it no children), accumulate adds its tally to the frame's counters. The counts
// are then the rays of the image, the same rays the megakernel and the tree wavefront trace.
#ifdef RT_COUNT_RAYS
inline global uint* Queue_PixelRays(global uint* rayTally, int pixel) {
    return rayTally + RT_RAY_TYPES * (pixel + 1);
}
#define QUEUE_COUNT_RAY(rayTally, pixel, type) atomic_inc(&Queue_PixelRays(rayTally, pixel)[type])
#define QUEUE_COUNT_INTO_PIXEL(sc, rayTally, pixel) \
    (sc).rayCounts = Queue_PixelRays(rayTally, pixel)
#else
#define QUEUE_COUNT_RAY(rayTally, pixel, type)
#define QUEUE_COUNT_INTO_PIXEL(sc, rayTally, pixel)
#endif

// From: pixels (retry list first, then a run of new ones) / To: pool slots [first, first + count).
kernel void Queue_Generate(RT_SCENE_PARAMS, QUEUE_RAYS_PARAMS(rays), int first, int count,
                           global const int* retry, int retryCount, int nextPixel,
                           global uint* rayTally) {
    int k = get_global_id(0);
    if (k >= count) return;
    RT_SCENE_INIT(sc);
    QUEUE_RAYS_INIT(rays);
    int pixel = k < retryCount ? retry[k] : nextPixel + (k - retryCount);
#ifdef RT_COUNT_RAYS
    if (k < retryCount) {  // the cut attempt's rays: retraced, not the image's
        global uint* tally = Queue_PixelRays(rayTally, pixel);
        for (int t = 0; t < RT_RAY_TYPES; ++t) {
            if (tally[t]) atomic_add(&rayTally[t], tally[t]);
            tally[t] = 0;
        }
    }
#endif
    int y = pixel / settings.width, x = pixel - y * settings.width;
    Pending p = PathState_Primary(&sc, x, y, settings.sampleIndex);
    Queue_Store(&rays, first + k, &p, pixel);
}

inline int Queue_Class(const SceneData* sc, const Node* node) {
    if (node->kind == RT_KIND_MISS) return RT_Q_MISS;
    Material m = sc->materials[node->material];
    return RT_Q_MATERIAL_CLASS(m);
}

// The shade queue extend puts a ray of class `cls` in (--queue-shade, RT_QUEUE_SHADE: the
// class's own queue unless the program was built for another mode).
inline int Queue_ShadeQueue(const SceneData* sc, const Node* node, int cls) {
#if RT_QUEUE_SHADE == RT_Q_SHADE_PATTERN
    if (cls == RT_Q_PROCEDURAL) return RT_Q_PATTERN_QUEUE(sc->materials[node->material].pattern);
#elif RT_QUEUE_SHADE == RT_Q_SHADE_SORT
    if (cls != RT_Q_MISS) return RT_Q_HITS;  // Queue_SortScatter orders them by material
#endif
    return cls;
}

// A work-group's pushes to the class queues, the shadow queue and the per-bounce histogram are
// counted in local memory (count, histogram) and reserved in the global counters once per group
// (base: the group's first slot in each queue). Every work-item of the group calls both.
inline void Queue_GroupPushesBegin(local int* count, local int* histogram, int lid, int size) {
    for (int k = lid; k < RT_Q_PUSHES; k += size) count[k] = 0;
    for (int k = lid; k < RT_Q_DEPTH_CLASSES; k += size) histogram[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
}

inline void Queue_GroupPushesReserve(local const int* count, local int* base,
                                     local const int* histogram, global int* counters, int lid,
                                     int size) {
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int k = lid; k < RT_Q_PUSHES; k += size)
        base[k] = count[k] ? atomic_add(&counters[RT_Q_COUNT + k], count[k]) : 0;
    for (int k = lid; k < RT_Q_DEPTH_CLASSES; k += size)
        if (histogram[k]) atomic_add(&counters[RT_Q_HISTOGRAM + k], histogram[k]);
    barrier(CLK_LOCAL_MEM_FENCE);
}

// From: pool [0, n) (n: see Queue_Length) / To: nodes[i], shade queues, shadow queue, per-bounce
// histogram. Pushes are aggregated per work-group in local memory: one global atomic per queue per
// group.
kernel void Queue_Extend(RT_SCENE_PARAMS, QUEUE_RAYS_PARAMS(rays), int n, global Node* nodes,
                         global int* shadeQueues, int pool, global int* shadowQueue,
                         global int* counters, int nWord, global uint* rayTally) {
    QUEUE_LOCAL_PAD();
    local int count[RT_Q_PUSHES], base[RT_Q_PUSHES];
    local int histogram[RT_Q_DEPTH_CLASSES];  // RT_Q_EXTEND_LOCAL_INTS in all
    int lid = get_local_id(0), size = get_local_size(0), i = get_global_id(0);
    n = Queue_Length(n, nWord, counters);
    // A launch sized by a bound has whole groups past the queue: they skip the local setup (the
    // test is the same for every work-item of a group, so no barrier is left half-reached).
    // The group's first index counts the global offset of a launch split into pieces.
    if (i - lid >= n) return;
    Queue_GroupPushesBegin(count, histogram, lid, size);
    int queue = -1, slot = 0, shadowSlot = -1;
    if (i < n) {
        RT_SCENE_INIT(sc);
        QUEUE_RAYS_INIT(rays);
        Pending p = Queue_Load(&rays, i);
        QUEUE_COUNT_INTO_PIXEL(sc, rayTally, rays.pixel[i]);
        Node node = RayTree_TraceSurface(&sc, p.ray, p.type);  // shadow rays: Queue_Shadow
        nodes[i] = node;
        int cls = Queue_Class(&sc, &node);
        queue = Queue_ShadeQueue(&sc, &node, cls);
        slot = atomic_inc(&count[queue]);
        atomic_inc(&histogram[p.depth * RT_Q_CLASSES + cls]);
        if (cls != RT_Q_MISS && settings.lightCount > 0)
            shadowSlot = atomic_inc(&count[RT_Q_QUEUES]);
    }
    Queue_GroupPushesReserve(count, base, histogram, counters, lid, size);
    if (queue >= 0) shadeQueues[queue * pool + base[queue] + slot] = i;
    if (shadowSlot >= 0) shadowQueue[base[RT_Q_QUEUES] + shadowSlot] = i;
}

// From: shadow queue, pool [0, n) / To: nodes[i].occluded. The shadow stage the other
// pipelines run inside RayTree_TraceNode, with the same sampler key (the ray's pixel, AA sample
// and depth).
kernel void Queue_Shadow(RT_SCENE_PARAMS, global Node* nodes, global const int* shadowQueue,
                         global const int* counters, global const int* rayPixel,
                         global const int* rayMeta, global uint* rayTally) {
    QUEUE_LOCAL_PAD();
    int k = get_global_id(0);
    if (k >= counters[RT_Q_SHADOW]) return;
    RT_SCENE_INIT(sc);
    int i = shadowQueue[k];
    Node node = nodes[i];
    int pixel = rayPixel[i], y = pixel / settings.width, x = pixel - y * settings.width;
    uint key = Sampling_PointKey(x, y, settings.sampleIndex, rayMeta[i] >> 8);
    QUEUE_COUNT_INTO_PIXEL(sc, rayTally, pixel);
    RayTree_CastShadows(&sc, &node, key);
    for (int j = 0; j < settings.lightCount; ++j) nodes[i].occluded[j] = node.occluded[j];
}

// One ray of class `cls` whose material has pattern `pattern`: its contribution to contrib[i],
// its children to staging slots [C i, C i + children). The kernel of a queue whose rays share
// both passes them as constants, so that it compiles to one code path; Queue_ShadeSorted passes
// the ray's class and RT_PATTERN_ANY (the material's pattern). The arithmetic is the same.
inline void Queue_Shade(const SceneData* sc, int cls, int pattern, int i, const QueueRays* rays,
                        global const Node* nodes, const QueueRays* staging, global float* contrib,
                        global int* children) {
    Pending p = Queue_Load(rays, i);
    float3 term;
    int c = 0;
    if (cls == RT_Q_MISS) {
        term = PathState_Miss(sc, &p);
    } else {
        Node node = nodes[i];
        Pending refl, refr;
        bool hasRefl, hasRefr;
        bool reflects = cls == RT_Q_MIRROR || cls == RT_Q_GLASS;
        term = PathState_Step(sc, &node, &p, reflects, cls == RT_Q_GLASS, pattern, &refl, &hasRefl,
                              &refr, &hasRefr);
        int pixel = rays->pixel[i];
        if (hasRefl) Queue_Store(staging, RT_BRANCH * i + c++, &refl, pixel);
        if (hasRefr) Queue_Store(staging, RT_BRANCH * i + c++, &refr, pixel);
    }
    vstore3(term, i, contrib);
    children[i] = c;
}

#define QUEUE_SHADE_PARAMS                                                   \
    RT_SCENE_PARAMS, QUEUE_RAYS_PARAMS(rays), global const Node *nodes,      \
        global const int *shadeQueues, int pool, global const int *counters, \
        QUEUE_RAYS_PARAMS(staging), global float *contrib, global int *children

// The shade kernel of queue `queue`, whose rays are all of class `cls` and pattern `pattern`.
#define QUEUE_SHADE_KERNEL(name, queue, cls, pattern)                                         \
    kernel void name(QUEUE_SHADE_PARAMS) {                                                    \
        QUEUE_LOCAL_PAD();                                                                    \
        int k = get_global_id(0);                                                             \
        if (k >= counters[RT_Q_COUNT + queue]) return;                                        \
        RT_SCENE_INIT(sc);                                                                    \
        QUEUE_RAYS_INIT(rays);                                                                \
        QUEUE_RAYS_INIT(staging);                                                             \
        Queue_Shade(&sc, cls, pattern, shadeQueues[queue * pool + k], &rays, nodes, &staging, \
                    contrib, children);                                                       \
    }

// From: class queue / To: contrib, children, staging.
QUEUE_SHADE_KERNEL(Queue_ShadeMiss, RT_Q_MISS, RT_Q_MISS, RT_PATTERN_NONE)
#if RT_QUEUE_SHADE != RT_Q_SHADE_SORT
QUEUE_SHADE_KERNEL(Queue_ShadeDiffuse, RT_Q_DIFFUSE, RT_Q_DIFFUSE, RT_PATTERN_NONE)
QUEUE_SHADE_KERNEL(Queue_ShadeMirror, RT_Q_MIRROR, RT_Q_MIRROR, RT_PATTERN_ANY)
QUEUE_SHADE_KERNEL(Queue_ShadeGlass, RT_Q_GLASS, RT_Q_GLASS, RT_PATTERN_ANY)
#endif
#if RT_QUEUE_SHADE == RT_Q_SHADE_CLASS
QUEUE_SHADE_KERNEL(Queue_ShadeProcedural, RT_Q_PROCEDURAL, RT_Q_PROCEDURAL, RT_PATTERN_ANY)
#elif RT_QUEUE_SHADE == RT_Q_SHADE_PATTERN
// From: pattern queue / To: as above. One kernel per pattern: a launch runs that pattern only.
#define QUEUE_SHADE_PATTERN_KERNEL(name, pattern) \
    QUEUE_SHADE_KERNEL(name, RT_Q_PATTERN_QUEUE(pattern), RT_Q_PROCEDURAL, pattern)
QUEUE_SHADE_PATTERN_KERNEL(Queue_ShadeChecker, RT_PATTERN_CHECKER)
QUEUE_SHADE_PATTERN_KERNEL(Queue_ShadeMarble, RT_PATTERN_MARBLE)
QUEUE_SHADE_PATTERN_KERNEL(Queue_ShadeWood, RT_PATTERN_WOOD)
QUEUE_SHADE_PATTERN_KERNEL(Queue_ShadeGranite, RT_PATTERN_GRANITE)
QUEUE_SHADE_PATTERN_KERNEL(Queue_ShadeBump, RT_PATTERN_BUMP)
#elif RT_QUEUE_SHADE == RT_Q_SHADE_SORT
// From: the hits sorted by material (queue_sort.cl) / To: as above. Every class and pattern in
// one launch, the class read per ray: neighbouring work-items shade the same material.
kernel void Queue_ShadeSorted(QUEUE_SHADE_PARAMS) {
    QUEUE_LOCAL_PAD();
    int k = get_global_id(0);
    if (k >= counters[RT_Q_COUNT + RT_Q_HITS]) return;
    RT_SCENE_INIT(sc);
    QUEUE_RAYS_INIT(rays);
    QUEUE_RAYS_INIT(staging);
    int i = shadeQueues[RT_Q_SORTED * pool + k];
    Material m = sc.materials[nodes[i].material];
    Queue_Shade(&sc, RT_Q_MATERIAL_CLASS(m), RT_PATTERN_ANY, i, &rays, nodes, &staging, contrib,
                children);
}
#endif

#include "queue_scan.cl"
#if RT_QUEUE_SHADE == RT_Q_SHADE_SORT
#include "queue_sort.cl"
#endif

#ifdef RT_QUEUE_PACKETS
#include "accel_wide_packet.cl"
#include "queue_packet.cl"
#endif
