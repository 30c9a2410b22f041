// rtlab — the scene as kernels see it, and the closest-hit / any-hit queries over it.
// Only the object kinds the scene uses are compiled (RT_HAS_SPHERES, RT_HAS_PLANES,
// RT_HAS_TRIANGLES), so a spheres-only program holds no triangle code at all. Spheres and
// triangles are found through the acceleration structure the RT_ACCEL_* define names
// (core/cl/accel.cl); planes are infinite and always tested one by one.
#ifndef RTLAB_CL_SCENE
#define RTLAB_CL_SCENE
#include "intersect.cl"

typedef struct SceneData {
    global const Sphere* spheres;
    global const Plane* planes;
    global const Triangle* triangles;
    global const MeshInstance* meshes;
    global const Kdop* kdops;  // RT_ACCEL_BV: one per mesh
    global const Light* lights;
    global const Material* materials;
    global const float* cubemap;
    global const BvhNode* bvh;  // RT_ACCEL_BVH: root at 0; RT_ACCEL_WIDE, _CWBVH: their nodes
    global const int* cells;    // RT_ACCEL_GRID: cell offsets, then references (core/accel.h);
                                // RT_ACCEL_CWBVH: CwbvhPrim records
    global uint* rayCounts;     // RT_RAY_* counters, written only when RT_COUNT_RAYS is defined
    RenderSettings settings;
} SceneData;

// Ray types (RT_RAY_*) are defined once in core/types.h, shared with the host.
#ifdef RT_COUNT_RAYS
#define RT_COUNT_RAY(sc, type) atomic_inc(&(sc)->rayCounts[type])
#else
#define RT_COUNT_RAY(sc, type)
#endif

// One step of a ray loop, as a warp takes it: its lowest active lane adds the number of active
// lanes and one step (core/types.h, RT_COUNT_LANES_ACTIVE). NVIDIA only (PTX's activemask and
// laneid), and only in the untimed counting frame: the host asks for it with RT_COUNT_LANES.
#if defined(RT_COUNT_RAYS) && defined(RT_COUNT_LANES)
#define RT_COUNT_WARP_STEP(sc)                                                      \
    do {                                                                            \
        uint rtMask_, rtLane_;                                                      \
        __asm__ volatile("activemask.b32 %0;" : "=r"(rtMask_));                     \
        __asm__ volatile("mov.u32 %0, %%laneid;" : "=r"(rtLane_));                  \
        if ((rtMask_ & ((1u << rtLane_) - 1u)) == 0u) {                             \
            atomic_add(&(sc)->rayCounts[RT_COUNT_LANES_ACTIVE], popcount(rtMask_)); \
            atomic_inc(&(sc)->rayCounts[RT_COUNT_WARP_STEPS]);                      \
        }                                                                           \
    } while (0)
#else
#define RT_COUNT_WARP_STEP(sc)
#endif

// Kernel parameters and their packing into a SceneData; every kernel takes the scene this way.
// The host binds them by these names (DeviceScene::setArgs, rt::Kernel), so renaming one here
// means renaming it there.
#define RT_SCENE_PARAMS                                                                           \
    global const Sphere *spheres, global const Plane *planes, global const Triangle *triangles,   \
        global const MeshInstance *meshes, global const Kdop *kdops, global const Light *lights,  \
        global const Material *materials, global const float *cubemap, global const BvhNode *bvh, \
        global const int *cells, global uint *rayCounts, const RenderSettings settings

#define RT_SCENE_INIT(sc)     \
    SceneData sc;             \
    sc.spheres = spheres;     \
    sc.planes = planes;       \
    sc.triangles = triangles; \
    sc.meshes = meshes;       \
    sc.kdops = kdops;         \
    sc.lights = lights;       \
    sc.materials = materials; \
    sc.cubemap = cubemap;     \
    sc.bvh = bvh;             \
    sc.cells = cells;         \
    sc.rayCounts = rayCounts; \
    sc.settings = settings

typedef struct Hit {
    float t;
    int kind;  // RT_KIND_*
    int object;
    float2 uv;  // triangle barycentrics
} Hit;

#include "accel.cl"

// No hit yet: t = tMax, kind RT_KIND_MISS.
inline Hit Hit_None(float tMax) {
    Hit hit;
    hit.t = tMax;
    hit.kind = RT_KIND_MISS;
    hit.object = -1;
    hit.uv = (float2)(0.0f, 0.0f);
    return hit;
}

#ifdef RT_HAS_PLANES
// The planes, one by one (they are infinite: no structure holds them). True when anyHit and one
// was accepted, so that the caller can stop there.
//
// Only programs whose scene has planes see this function or a call to it. NVIDIA's OpenCL
// compiler (driver 580.159.04) did not finish building, in minutes, a program with spheres and
// triangles in which a stub of it that returned false sat between Scene_Query's sphere and
// triangle loops (clBuildProgram busy on one core, nothing launched). Without the stub it builds
// them in seconds.
inline bool Scene_Planes(const SceneData* sc, Ray ray, Hit* hit, bool anyHit) {
    for (int i = 0; i < sc->settings.planeCount; ++i) {
        float t = Plane_Intersect(ray, f3(sc->planes[i].normal), sc->planes[i].offset);
        if (t > 0.0f && t < hit->t) {
            hit->t = t;
            hit->kind = RT_KIND_PLANE;
            hit->object = i;
            if (anyHit) return true;
        }
    }
    return false;
}
#endif

// Closest hit with 0 < t < tMax, or with anyHit the first one found (shadow rays stop there).
// Without a grid or BVH the order is spheres, planes, triangles (mesh by mesh) and ties keep
// the first object (core/SHADING.md section 2); with one, planes come first.
RT_QUERY_LINKAGE Hit Scene_Query(const SceneData* sc, Ray ray, float tMax, bool anyHit) {
    Hit hit = Hit_None(tMax);
#if defined(RT_ACCEL_GRID) || defined(RT_ACCEL_BVH) || defined(RT_ACCEL_WIDE) || \
    defined(RT_ACCEL_CWBVH)
#ifdef RT_HAS_PLANES
    if (Scene_Planes(sc, ray, &hit, anyHit)) return hit;
#endif
#ifdef RT_ACCEL_GRID
    Grid_Query(sc, ray, &hit, anyHit);
#elif defined(RT_ACCEL_WIDE)
    Wide_Query(sc, ray, &hit, anyHit);
#elif defined(RT_ACCEL_CWBVH)
    Cwbvh_Query(sc, ray, &hit, anyHit);
#else
    Bvh_Query(sc, ray, &hit, anyHit);
#endif
#else
#ifdef RT_HAS_SPHERES
    for (int i = 0; i < sc->settings.sphereCount; ++i)
        if (Hit_Sphere(sc, i, ray, &hit) && anyHit) return hit;
#endif
#ifdef RT_HAS_PLANES
    if (Scene_Planes(sc, ray, &hit, anyHit)) return hit;
#endif
#ifdef RT_HAS_TRIANGLES
    for (int m = 0; m < sc->settings.meshCount; ++m)
        if (Mesh_Query(sc, m, ray, &hit, anyHit) && anyHit) return hit;
#endif
#endif
    return hit;
}

inline Hit Scene_Intersect(const SceneData* sc, Ray ray, float tMax) {
    return Scene_Query(sc, ray, tMax, false);
}

// Any hit with 0 < t < tMax (shadow rays). Transparent objects occlude like opaque ones.
inline bool Scene_Occluded(const SceneData* sc, Ray ray, float tMax) {
    return Scene_Query(sc, ray, tMax, true).kind != RT_KIND_MISS;
}

#endif
