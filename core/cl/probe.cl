// rtlab — device probes for the tests: record layouts as the OpenCL compiler sees them, and
// single rays through the shared intersection code (built with and without the robust defines).
#include "intersect.cl"

kernel void Probe_Sizes(global uint* out) {
    out[0] = sizeof(Float3);
    out[1] = sizeof(Material);
    out[2] = sizeof(Sphere);
    out[3] = sizeof(Plane);
    out[4] = sizeof(Triangle);
    out[5] = sizeof(MeshInstance);
    out[6] = sizeof(Light);
    out[7] = sizeof(Camera);
    out[8] = sizeof(RenderSettings);
    out[9] = sizeof(Node);
    out[10] = sizeof(BvhNode);
    out[11] = __builtin_offsetof(Node, occluded);
    out[12] = __builtin_offsetof(RenderSettings, camera);
    out[13] = __builtin_offsetof(MeshInstance, sphereRadius);
    out[14] = sizeof(Grid);
    out[15] = sizeof(Kdop);
    out[16] = __builtin_offsetof(RenderSettings, grid);
}

// One ray per work-item against one sphere: in = origin, dir, centre, radius (10 floats).
kernel void Probe_Sphere(global const float* in, global float* t) {
    size_t i = get_global_id(0);
    global const float* r = in + i * 10;
    Ray ray = makeRay((float3)(r[0], r[1], r[2]), (float3)(r[3], r[4], r[5]));
    t[i] = Sphere_Intersect(ray, (float3)(r[6], r[7], r[8]), r[9]);
}

#ifdef RT_HAS_TRIANGLES
// One ray per work-item (origin, dir: 6 floats) against every triangle (9 floats each); counts
// the triangles it hits. A ray from inside a closed mesh must hit at least one.
kernel void Probe_TriangleHits(global const float* rays, global const float* tris, int count,
                               global int* hits) {
    size_t i = get_global_id(0);
    global const float* r = rays + i * 6;
    Ray ray = makeRay((float3)(r[0], r[1], r[2]), (float3)(r[3], r[4], r[5]));
    int n = 0;
    for (int k = 0; k < count; ++k) {
        global const float* v = tris + k * 9;
        float2 uv;
        float t = Triangle_Intersect(ray, (float3)(v[0], v[1], v[2]), (float3)(v[3], v[4], v[5]),
                                     (float3)(v[6], v[7], v[8]), &uv);
        if (t > 0.0f) ++n;
    }
    hits[i] = n;
}
#endif
