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
                                     (float3)(v[6], v[7], v[8]), INFINITY, &uv);
        if (t > 0.0f) ++n;
    }
    hits[i] = n;
}
#endif

// ---- stability probes (tests/stability_test.cpp, apps/stress.cpp) ----
// Built with a scene's featureDefines (which always define RT_BRANCH) and bound with
// DeviceScene::setArgs, so the rays go through the real closest-hit query, acceleration
// structure, shading normal and secondary-ray offset of both pipelines.
#ifdef RT_BRANCH
#include "raytree.cl"

// Closest hit of one ray per work-item (origin, dir: 6 floats) over the whole scene:
// t (-1 on a miss) and (kind, object).
kernel void Probe_Closest(RT_SCENE_PARAMS, global const float* rays, global float* t,
                          global int2* what) {
    size_t i = get_global_id(0);
    RT_SCENE_INIT(sc);
    global const float* r = rays + i * 6;
    Hit h = Scene_Intersect(&sc, makeRay((float3)(r[0], r[1], r[2]), (float3)(r[3], r[4], r[5])),
                            INFINITY);
    t[i] = h.kind == RT_KIND_MISS ? -1.0f : h.t;
    what[i] = (int2)(h.kind, h.object);
}

// A uniform direction on the sphere from two hashed integers (PCG-style mixing).
inline uint Probe_Hash(uint x) {
    x = x * 747796405u + 2891336453u;
    x = ((x >> ((x >> 28u) + 4u)) ^ x) * 277803737u;
    return (x >> 22u) ^ x;
}

inline float3 Probe_Direction(uint a, uint b) {
    uint h1 = Probe_Hash(a * 9781u + Probe_Hash(b)), h2 = Probe_Hash(h1 ^ 0x9e3779b9u);
    float z = 1.0f - 2.0f * ((float)(h1 >> 8) + 0.5f) / 16777216.0f;
    float phi = 6.2831853f * ((float)(h2 >> 8) / 16777216.0f);
    float s = sqrt(fmax(0.0f, 1.0f - z * z));
    return (float3)(s * cos(phi), s * sin(phi), z);
}

// Self-intersection of secondary rays (pbrt-v4's Triangle.Reintersect, over a whole scene): the
// primary ray per work-item (6 floats) is traced as the pipelines trace it; from its hit,
// `spawn` random directions leave like reflection/shadow rays (p + offset N, on the outer side
// of the geometric normal) or refraction rays (p - offset N, inner side). Per work-item out[8]:
//   0 kind hit (0 = miss: nothing spawned)    1 outward rays   2 outward re-hits of the object
//   3 inward rays                             4 inward re-hits of the same triangle, or of the
//   same sphere within 1e-3 r (acne)          5 inward rays that left the object without
//   hitting it (the origin was pushed through it: an over-large offset)
kernel void Probe_Spawn(RT_SCENE_PARAMS, global const float* rays, int spawn, global int* out) {
    size_t i = get_global_id(0);
    RT_SCENE_INIT(sc);
    global const float* r = rays + i * 6;
    Ray ray = makeRay((float3)(r[0], r[1], r[2]), (float3)(r[3], r[4], r[5]));
    Node node = RayTree_TraceNode(&sc, ray, RT_RAY_PRIMARY, 0u);  // no pixel: one fixed key
    global int* o = out + i * 8;
    for (int k = 0; k < 8; ++k) o[k] = 0;
    o[0] = node.kind;
    if (node.kind == RT_KIND_MISS || node.kind == RT_KIND_PLANE) return;
    float3 ng = f3(node.normal);
    float radius = 0.0f;
    int mesh = -1;
#ifdef RT_HAS_TRIANGLES
    if (node.kind == RT_KIND_TRIANGLE) {
        Triangle tri = sc.triangles[node.object];
        ng = normalize(cross(f3(tri.v1) - f3(tri.v0), f3(tri.v2) - f3(tri.v0)));
        if (dot(ng, ray.dir) > 0.0f) ng = -ng;
        mesh = tri.mesh;
    }
#endif
#ifdef RT_HAS_SPHERES
    if (node.kind == RT_KIND_SPHERE) radius = sc.spheres[node.object].radius;
#endif
    // The origins the pipelines give reflection/shadow rays and refraction rays.
    float3 outer = RayTree_SpawnOrigin(&sc, &node, 1.0f);
    float3 inner = RayTree_SpawnOrigin(&sc, &node, -1.0f);
    for (int k = 0; k < spawn; ++k) {
        float3 w = Probe_Direction((uint)i, (uint)k);
        float cosG = dot(w, ng);
        if (cosG == 0.0f) continue;
        bool out_ = cosG > 0.0f;
        Hit h = Scene_Intersect(&sc, makeRay(out_ ? outer : inner, w), INFINITY);
        bool sameObject =
            h.kind == node.kind && (node.kind == RT_KIND_SPHERE ? h.object == node.object : false);
#ifdef RT_HAS_TRIANGLES
        if (node.kind == RT_KIND_TRIANGLE && h.kind == RT_KIND_TRIANGLE)
            sameObject = sc.triangles[h.object].mesh == mesh;
#endif
        if (out_) {
            o[1] += 1;
            if (sameObject) o[2] += 1;
        } else {
            o[3] += 1;
            bool acne = node.kind == RT_KIND_TRIANGLE
                            ? (h.kind == RT_KIND_TRIANGLE && h.object == node.object)
                            : (sameObject && h.t < 1e-3f * radius && -cosG > 1e-3f);
            if (acne) o[4] += 1;
            if (!sameObject) o[5] += 1;
        }
    }
}

#ifdef RT_HAS_TRIANGLES
// pbrt-v4's Triangle.Reintersect for lone triangles (9 floats each, any scale): the ray from
// origin[i] (3 floats) toward target[i] (3 floats, a point inside the triangle) hits it at
// p = o + t d, as the pipelines compute hit points; `spawn` random directions then leave p with
// the pipelines' offset to the side they point to. out[i] = re-hits of the same triangle, or -1
// when the first ray missed.
kernel void Probe_Reintersect(global const float* tris, global const float* origins,
                              global const float* targets, int spawn, global int* out) {
    size_t i = get_global_id(0);
    global const float* v = tris + i * 9;
    float3 v0 = (float3)(v[0], v[1], v[2]), v1 = (float3)(v[3], v[4], v[5]),
           v2 = (float3)(v[6], v[7], v[8]);
    float3 org = vload3(i, origins), d = normalize(vload3(i, targets) - org);
    float2 uv;
    float t = Triangle_Intersect(makeRay(org, d), v0, v1, v2, INFINITY, &uv);
    if (!(t > 0.0f)) {
        out[i] = -1;
        return;
    }
    float3 n = normalize(cross(v1 - v0, v2 - v0));
    if (dot(n, d) > 0.0f) n = -n;
#ifdef RT_BOUND_OFFSET
    float3 p = (1.0f - uv.x - uv.y) * v0 + uv.x * v1 + uv.y * v2;  // as RayTree_TraceNode
    float3 outer = Shade_SpawnOrigin(p, n, Shade_TriangleError(v0, v1, v2), 1.0f);
    float3 inner = Shade_SpawnOrigin(p, n, Shade_TriangleError(v0, v1, v2), -1.0f);
#else
    float3 p = org + t * d;
    float eps = Shade_Offset(p);
    float3 outer = p + eps * n, inner = p + (-eps) * n;
#endif
    int hits = 0;
    for (int k = 0; k < spawn; ++k) {
        float3 w = Probe_Direction((uint)i, (uint)k);
        bool out_ = dot(w, n) >= 0.0f;
        if (Triangle_Intersect(makeRay(out_ ? outer : inner, w), v0, v1, v2, INFINITY, &uv) > 0.0f)
            ++hits;
    }
    out[i] = hits;
}
#endif

// Refraction and Fresnel at one interface (section 6, 7) per work-item: in = d (3), n (3, facing
// the incoming ray), eta = n1/n2, n1, n2; out = refracted (1 or 0), t (3), F.
kernel void Probe_Refract(global const float* in, global float* out) {
    size_t i = get_global_id(0);
    global const float* a = in + i * 9;
    float3 d = (float3)(a[0], a[1], a[2]), n = (float3)(a[3], a[4], a[5]);
    float3 t = (float3)(0.0f, 0.0f, 0.0f);
    bool ok = Shade_Refract(d, n, a[6], &t);
    global float* o = out + i * 5;
    o[0] = ok ? 1.0f : 0.0f;
    o[1] = t.x;
    o[2] = t.y;
    o[3] = t.z;
    o[4] = Shade_Fresnel(-dot(d, n), a[7], a[8]);
}

#ifdef RT_TREE_NODES
// The colour of a whole ray tree (tree layout, as Megakernel_Sample) from a given primary ray
// per work-item (6 floats): what a pixel would hold if its camera ray were this one.
kernel void Probe_Shade(RT_SCENE_PARAMS, global const float* rays, global float* rgb) {
    size_t i = get_global_id(0);
    RT_SCENE_INIT(sc);
    global const float* r = rays + i * 6;
    Node nodes[RT_TREE_NODES];
    float3 colors[RT_TREE_NODES];
    // Rays without a pixel: the sampler key of pixel i of row 0, sample 0.
    nodes[0] =
        RayTree_TraceNode(&sc, makeRay((float3)(r[0], r[1], r[2]), (float3)(r[3], r[4], r[5])),
                          RT_RAY_PRIMARY, Sampling_PointKey((int)i, 0, 0, 0));
    for (int k = 1; k < RT_TREE_NODES; ++k) {
        int parent = (k - 1) / RT_BRANCH;
        Ray ray;
        if (RayTree_ChildRay(&sc, &nodes[parent], RayTree_Depth(parent), k - 1 - parent * RT_BRANCH,
                             &ray))
            nodes[k] = RayTree_TraceNode(&sc, ray, RayTree_SlotType(k),
                                         Sampling_PointKey((int)i, 0, 0, RayTree_Depth(k)));
        else
            nodes[k].flags = 0;
    }
    vstore3(RayTree_Combine(&sc, nodes, colors), i, rgb);
}
#endif  // RT_TREE_NODES
#endif  // RT_BRANCH
