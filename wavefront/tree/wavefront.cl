// rtlab — the report's wavefront pipeline (3.2.1 to 3.2.3): three kernels around a global ray tree
// of W x rows x N nodes. Pixel (x, y) of a tile starting at settings.rowOffset owns the slice at
// ((y - rowOffset) * W + x) * N. Shadow rays are cast in trace and stored as occlusion counts in
// the node (4 bytes), so image does no ray casting: it only shades and mixes. This keeps the
// expensive, divergent traversal in one kernel and the image kernel a pure streaming pass.
#include "raytree.cl"

inline size_t Wavefront_Slice(const RenderSettings* s, int x, int y) {
    return ((size_t)(y - s->rowOffset) * (size_t)s->width + (size_t)x) * RT_TREE_NODES;
}

// Traces the primary ray and every secondary ray of the pixel's tree for AA sample
// settings.sampleIndex. Untraced slots are left alone: reset has cleared their flags.
// rowEnd: one past the tile's last row. GPU launches round the tile up to whole work-groups, and
// rows past the tile have no slice in the tree buffer.
kernel void Wavefront_Trace(RT_SCENE_PARAMS, global Node* tree, int rowEnd) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= rowEnd) return;
    RT_SCENE_INIT(sc);
    global Node* slice = tree + Wavefront_Slice(&settings, x, y);
    slice[0] = RayTree_TraceNode(&sc, RayTree_PrimaryRay(&sc, x, y, settings.sampleIndex),
                                 RT_RAY_PRIMARY, Sampling_PointKey(x, y, settings.sampleIndex, 0));
    for (int i = 1; i < RT_TREE_NODES; ++i) {
        int parent = (i - 1) / RT_BRANCH;
        Node p = slice[parent];  // written earlier by this same work-item
        Ray ray;
        if (RayTree_ChildRay(&sc, &p, RayTree_Depth(parent), i - 1 - parent * RT_BRANCH, &ray))
            slice[i] = RayTree_TraceNode(
                &sc, ray, RayTree_SlotType(i),
                Sampling_PointKey(x, y, settings.sampleIndex, RayTree_Depth(i)));
    }
}

// Copies the pixel's slice to private memory, combines it bottom-up, and accumulates the AA
// sample into the image: the first sample stores, later ones add, the last divides.
kernel void Wavefront_Image(RT_SCENE_PARAMS, global const Node* tree, global float* image,
                            int rowEnd) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= rowEnd) return;
    RT_SCENE_INIT(sc);
    global const Node* slice = tree + Wavefront_Slice(&settings, x, y);
    Node nodes[RT_TREE_NODES];
    float3 colors[RT_TREE_NODES];
    for (int i = 0; i < RT_TREE_NODES; ++i) nodes[i] = slice[i];
    float3 c = RayTree_Combine(&sc, nodes, colors);
    int o = (y * settings.width + x) * 3;
    if (settings.sampleIndex > 0) c += (float3)(image[o], image[o + 1], image[o + 2]);
    int samples = settings.aaSamples * settings.aaSamples;
    if (settings.sampleIndex == samples - 1) c = c / (float)samples;
    image[o] = c.x;
    image[o + 1] = c.y;
    image[o + 2] = c.z;
}

// Clears the traced flag of every node (1D range over the tree), ready for the next pass.
kernel void Wavefront_Reset(global Node* tree, uint count) {
    size_t i = get_global_id(0);
    if (i < count) tree[i].flags = 0;
}
