// rtlab — the scene as kernels see it, and the closest-hit / any-hit queries over it.
// Only the object kinds the scene uses are compiled (RT_HAS_SPHERES, RT_HAS_PLANES,
// RT_HAS_TRIANGLES), so a spheres-only program holds no triangle code at all.
#ifndef RTLAB_CL_SCENE
#define RTLAB_CL_SCENE
#include "intersect.cl"

typedef struct SceneData {
    global const Sphere* spheres;
    global const Plane* planes;
    global const Triangle* triangles;
    global const MeshInstance* meshes;
    global const Light* lights;
    global const Material* materials;
    global const float* cubemap;
    global const BvhNode* bvh;
    global uint* rayCounts;  // RT_RAY_* counters, written only when RT_COUNT_RAYS is defined
    RenderSettings settings;
} SceneData;

// Ray types for the device-side ray counters.
#define RT_RAY_PRIMARY 0
#define RT_RAY_REFLECTION 1
#define RT_RAY_REFRACTION 2
#define RT_RAY_SHADOW 3

#ifdef RT_COUNT_RAYS
#define RT_COUNT_RAY(sc, type) atomic_inc(&(sc)->rayCounts[type])
#else
#define RT_COUNT_RAY(sc, type)
#endif

// Kernel parameters and their packing into a SceneData; every kernel takes the scene this way.
#define RT_SCENE_PARAMS                                                                     \
    global const Sphere *spheres, global const Plane *planes,                               \
        global const Triangle *triangles, global const MeshInstance *meshes,                \
        global const Light *lights, global const Material *materials,                       \
        global const float *cubemap, global const BvhNode *bvh, global uint *rayCounts,      \
        const RenderSettings settings

#define RT_SCENE_INIT(sc)          \
    SceneData sc;                  \
    sc.spheres = spheres;          \
    sc.planes = planes;            \
    sc.triangles = triangles;      \
    sc.meshes = meshes;            \
    sc.lights = lights;            \
    sc.materials = materials;      \
    sc.cubemap = cubemap;          \
    sc.bvh = bvh;                  \
    sc.rayCounts = rayCounts;      \
    sc.settings = settings

typedef struct Hit {
    float t;
    int kind;  // RT_KIND_*
    int object;
    float2 uv;  // triangle barycentrics
} Hit;

#ifdef RT_HAS_TRIANGLES
// Closest triangle of one mesh; updates hit when nearer. Brute force or BVH (issue 5).
inline void Mesh_Intersect(const SceneData* sc, int m, Ray ray, float3 invDir, Hit* hit) {
    MeshInstance mesh = sc->meshes[m];
#if defined(RT_ACCEL_BV)
    // Preliminary bounding volumes (report 2.2.2): sphere, then box.
    float3 oc = ray.origin - f3(mesh.sphereCenter);
    float b = dot(oc, ray.dir);
    float c = dot(oc, oc) - mesh.sphereRadius * mesh.sphereRadius;
    if (c > 0.0f && (b > 0.0f || b * b - c < 0.0f)) return;
    if (!Aabb_Hit(ray, invDir, f3(mesh.boundsLo), f3(mesh.boundsHi), hit->t)) return;
#endif
#if defined(RT_ACCEL_BVH)
    int stack[64];
    int top = 0;
    stack[top++] = mesh.bvhRoot;
    while (top > 0) {
        BvhNode node = sc->bvh[stack[--top]];
        if (!Aabb_Hit(ray, invDir, f3(node.lo), f3(node.hi), hit->t)) continue;
        if (node.count > 0) {
            for (int i = node.first; i < node.first + node.count; ++i) {
                Triangle tri = sc->triangles[i];
                float2 uv;
                float t = Triangle_Intersect(ray, f3(tri.v0), f3(tri.v1), f3(tri.v2), &uv);
                if (t > 0.0f && t < hit->t) {
                    hit->t = t;
                    hit->kind = RT_KIND_TRIANGLE;
                    hit->object = i;
                    hit->uv = uv;
                }
            }
        } else if (top < 63) {
            stack[top++] = node.first + 1;
            stack[top++] = node.first;
        }
    }
#else
    for (int i = mesh.firstTriangle; i < mesh.firstTriangle + mesh.triangleCount; ++i) {
        Triangle tri = sc->triangles[i];
        float2 uv;
        float t = Triangle_Intersect(ray, f3(tri.v0), f3(tri.v1), f3(tri.v2), &uv);
        if (t > 0.0f && t < hit->t) {
            hit->t = t;
            hit->kind = RT_KIND_TRIANGLE;
            hit->object = i;
            hit->uv = uv;
        }
    }
#endif
}
#endif

// Closest hit with 0 < t < tMax, in the order spheres, planes, triangles; ties keep the first.
inline Hit Scene_Intersect(const SceneData* sc, Ray ray, float tMax) {
    Hit hit;
    hit.t = tMax;
    hit.kind = RT_KIND_MISS;
    hit.object = -1;
    hit.uv = (float2)(0.0f, 0.0f);
#ifdef RT_HAS_SPHERES
    for (int i = 0; i < sc->settings.sphereCount; ++i) {
        float t = Sphere_Intersect(ray, f3(sc->spheres[i].center), sc->spheres[i].radius);
        if (t > 0.0f && t < hit.t) {
            hit.t = t;
            hit.kind = RT_KIND_SPHERE;
            hit.object = i;
        }
    }
#endif
#ifdef RT_HAS_PLANES
    for (int i = 0; i < sc->settings.planeCount; ++i) {
        float t = Plane_Intersect(ray, f3(sc->planes[i].normal), sc->planes[i].offset);
        if (t > 0.0f && t < hit.t) {
            hit.t = t;
            hit.kind = RT_KIND_PLANE;
            hit.object = i;
        }
    }
#endif
#ifdef RT_HAS_TRIANGLES
    float3 invDir = 1.0f / ray.dir;
    for (int m = 0; m < sc->settings.meshCount; ++m) Mesh_Intersect(sc, m, ray, invDir, &hit);
#endif
    return hit;
}

// Any hit with 0 < t < tMax (shadow rays). Transparent objects occlude like opaque ones.
inline bool Scene_Occluded(const SceneData* sc, Ray ray, float tMax) {
#ifdef RT_HAS_SPHERES
    for (int i = 0; i < sc->settings.sphereCount; ++i) {
        float t = Sphere_Intersect(ray, f3(sc->spheres[i].center), sc->spheres[i].radius);
        if (t > 0.0f && t < tMax) return true;
    }
#endif
#ifdef RT_HAS_PLANES
    for (int i = 0; i < sc->settings.planeCount; ++i) {
        float t = Plane_Intersect(ray, f3(sc->planes[i].normal), sc->planes[i].offset);
        if (t > 0.0f && t < tMax) return true;
    }
#endif
#ifdef RT_HAS_TRIANGLES
    // The closest-hit query bounded by tMax; a dedicated any-hit traversal is not worth a second
    // copy of the mesh loop at these scene sizes.
    float3 invDir = 1.0f / ray.dir;
    Hit hit;
    hit.t = tMax;
    hit.kind = RT_KIND_MISS;
    for (int m = 0; m < sc->settings.meshCount; ++m) {
        Mesh_Intersect(sc, m, ray, invDir, &hit);
        if (hit.kind != RT_KIND_MISS) return true;
    }
#endif
    return false;
}

#endif
