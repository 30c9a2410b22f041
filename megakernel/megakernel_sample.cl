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

inline float3 Megakernel_Sample(const SceneData* sc, int x, int y, int sample) {
    Pending stack[RT_STACK_SIZE];
    int top = 0;
    stack[top++] = PathState_Primary(sc, x, y, sample);
    float3 color = (float3)(0.0f, 0.0f, 0.0f);
    while (top > 0) {
        RT_COUNT_WARP_STEP(sc);  // the lanes that still have a ray to trace
        Pending p = stack[--top];
        Node node = RayTree_TraceNode(sc, p.ray, p.type, Sampling_PointKey(x, y, sample, p.depth));
        if (node.kind == RT_KIND_MISS) {
            color += PathState_Miss(sc, &p);
            continue;
        }
        Pending refl, refr;
        bool hasRefl, hasRefr;
        color += PathState_Step(sc, &node, &p, true, true, &refl, &hasRefl, &refr, &hasRefr);
        // Depth-first: at most one pending sibling per level, so B*(C-1)+1 entries suffice.
        if (hasRefr) stack[top++] = refr;
        if (hasRefl) stack[top++] = refl;
    }
    return color;
}
#endif

inline void Megakernel_Store(global float* image, int i, float3 c) {
    image[i] = c.x;
    image[i + 1] = c.y;
    image[i + 2] = c.z;
}
