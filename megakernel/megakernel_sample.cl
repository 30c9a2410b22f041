// rtlab — the megakernel's per-pixel work (report 3.2.4): one work-item takes its pixel from the
// primary ray to the final colour; the kernels that schedule it include this file
// (megakernel.cl, persistent/persistent.cl). OpenCL C has no recursion, so the ray tree lives in
// private memory, in one of two layouts chosen at build time:
//   RT_LAYOUT_TREE      the report's design: all N = RT_TREE_NODES nodes in heap order, traced
//                       top-down and combined bottom-up with the same functions as the wavefront
//                       image kernel;
//   RT_LAYOUT_WEIGHTED  a depth-first stack of at most RT_STACK_SIZE = B*(C-1)+1 pending rays,
//                       each carrying the weight its parent gives it, added straight into the
//                       pixel (core/cl/pathstate.cl, shared with the queue wavefront).
#include "pathstate.cl"  // Pending and the forward-weight step (weighted layout)

#ifdef RT_LAYOUT_TREE
inline float3 Megakernel_Sample(const SceneData* sc, int x, int y, int sample) {
    Node nodes[RT_TREE_NODES];
    float3 colors[RT_TREE_NODES];
    RT_COUNT_WARP_STEP(sc);
    nodes[0] = RayTree_TraceNode(sc, RayTree_PrimaryRay(sc, x, y, sample), RT_RAY_PRIMARY,
                                 Sampling_PointKey(x, y, sample, 0));
    for (int i = 1; i < RT_TREE_NODES; ++i) {
        int parent = (i - 1) / RT_BRANCH;
        Ray ray;
        if (RayTree_ChildRay(sc, &nodes[parent], RayTree_Depth(parent), i - 1 - parent * RT_BRANCH,
                             &ray)) {
            RT_COUNT_WARP_STEP(sc);  // the lanes that trace slot i
            nodes[i] = RayTree_TraceNode(sc, ray, RayTree_SlotType(i),
                                         Sampling_PointKey(x, y, sample, RayTree_Depth(i)));
        } else {
            nodes[i].flags = 0;
        }
    }
    return RayTree_Combine(sc, nodes, colors);
}
#else

#ifdef RT_PACKED_STACK
// The register-pressure study's smaller stack record (scripts/register-study): 40 bytes a
// pending ray instead of Pending's 64 (a float3 takes 16), three packed Float3 and the depth and
// type in one word. The same values, so the same image.
// clang-format off
typedef struct PackedPending {
    RT_RAY_STATE_MEMBERS  // core/ray_state.h: three packed Float3 and depth << 8 | type
} PackedPending;
// clang-format on
RAY_STATE_CODEC(PackedPending)
inline PackedPending Megakernel_Pack(Pending p) {
    PackedPending q;
    RayState_Pack_PackedPending(&p, &q);
    return q;
}
inline Pending Megakernel_Unpack(PackedPending q) { return RayState_Unpack_PackedPending(q); }
#define RT_STACK_RECORD PackedPending
#define RT_STACK_PUSH(p) Megakernel_Pack(p)
#define RT_STACK_POP(q) Megakernel_Unpack(q)
#else
#define RT_STACK_RECORD Pending
#define RT_STACK_PUSH(p) (p)
#define RT_STACK_POP(q) (q)
#endif

// One step of a path: pops the top pending ray of pixel (x, y)'s sample `sample`, traces it,
// pushes its children and returns what it adds to the pixel. Both schedules of the weighted
// layout take their steps here: Megakernel_Sample below, one sample at a time, and the persistent
// megakernel, whose lanes start a new pixel when their stack runs dry.
inline float3 Megakernel_TraceNext(const SceneData* sc, RT_STACK_RECORD* stack, int* top, int x,
                                   int y, int sample) {
    Pending p = RT_STACK_POP(stack[--*top]);
    Node node = RayTree_TraceNode(sc, p.ray, p.type, Sampling_PointKey(x, y, sample, p.depth));
    if (node.kind == RT_KIND_MISS) return PathState_Miss(sc, &p);
    Pending refl, refr;
    bool hasRefl, hasRefr;
    const float3 term =
        PathState_Step(sc, &node, &p, true, true, RT_PATTERN_ANY, &refl, &hasRefl, &refr, &hasRefr);
    // Depth-first: at most one pending sibling per level, so B*(C-1)+1 entries suffice.
    if (hasRefr) stack[(*top)++] = RT_STACK_PUSH(refr);
    if (hasRefl) stack[(*top)++] = RT_STACK_PUSH(refl);
    return term;
}

inline float3 Megakernel_Sample(const SceneData* sc, int x, int y, int sample) {
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0;
    stack[top++] = RT_STACK_PUSH(PathState_Primary(sc, x, y, sample));
    float3 color = (float3)(0.0f, 0.0f, 0.0f);
    while (top > 0) {
        RT_COUNT_WARP_STEP(sc);  // the lanes that still have a ray to trace
        color += Megakernel_TraceNext(sc, stack, &top, x, y, sample);
    }
    return color;
}
#endif

// The mean of the pixel's `samples` AA samples, summed in sample order. Megakernel_Sample has one
// call site here, so that its code is inlined once: the first sample apart from the others, as
// `acc = Sample(0); for (s = 1...) acc += Sample(s)`, inlines it twice, and on NVIDIA the larger
// kernel runs slower at the same registers. Starting the sum at +0 rather than at the first
// sample changes no value (a -0 would become +0, which compares equal).
inline float3 Megakernel_PixelMean(const SceneData* sc, int x, int y, int samples) {
    float3 acc = (float3)(0.0f, 0.0f, 0.0f);
    for (int s = 0; s < samples; ++s) acc += Megakernel_Sample(sc, x, y, s);
    return acc / (float)samples;
}

inline void Megakernel_Store(global float* image, int i, float3 c) {
    image[i] = c.x;
    image[i + 1] = c.y;
    image[i + 2] = c.z;
}
