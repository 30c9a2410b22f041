// rtlab — acceleration structures on the device (built by core/accel*.cpp). Each query
// takes the current hit and only accepts 0 < t < hit->t; with anyHit it returns at the first
// primitive it accepts (shadow rays), otherwise it finds the closest. Included by scene.cl after
// SceneData and Hit; RT_ACCEL_BV, RT_ACCEL_GRID, RT_ACCEL_BVH, RT_ACCEL_WIDE (accel_wide.cl) or
// RT_ACCEL_CWBVH (accel_cwbvh.cl) picks the structure.
#ifndef RTLAB_CL_ACCEL
#define RTLAB_CL_ACCEL

// 1 / d with zero components replaced by a tiny value of the same sign, so that a slab product
// is never 0 * inf = NaN for a ray that starts on a box face.
inline float3 Ray_InvDir(float3 d) {
    float3 tiny = copysign((float3)(1e-20f), d);
    return 1.0f / select(d, tiny, fabs(d) < (float3)(1e-20f));
}

// Minimum and maximum for the slab tests, in each device's cheapest form. On a CPU a plain
// compare-and-select is one instruction where fmin/fmax add a NaN fix-up; on a GPU fmin/fmax
// is the one instruction, and compare-and-select two. A box test is mostly minima and maxima,
// so the wrong form shows directly in every structure's rays/s. The slab distances are NaN only
// for a ray with a NaN component, which no primitive test accepts either (Ray_InvDir keeps 1/d
// finite), so both forms give the same hits. RT_DEVICE_CPU comes from core/cl_runtime.cpp.
#ifdef RT_DEVICE_CPU
inline float Min_Fast(float a, float b) { return a < b ? a : b; }
inline float Max_Fast(float a, float b) { return a > b ? a : b; }
inline float3 Min3_Fast(float3 a, float3 b) { return select(b, a, a < b); }
inline float3 Max3_Fast(float3 a, float3 b) { return select(b, a, a > b); }
#else
inline float Min_Fast(float a, float b) { return fmin(a, b); }
inline float Max_Fast(float a, float b) { return fmax(a, b); }
inline float3 Min3_Fast(float3 a, float3 b) { return fmin(a, b); }
inline float3 Max3_Fast(float3 a, float3 b) { return fmax(a, b); }
#endif

// Distance at which the ray enters the box, if it does so before tMax; INFINITY otherwise.
// Each slab distance is one fused multiply-add, lo * invDir - origin * invDir, the product of
// origin and inverse direction hoisted out of the traversal loop by the compiler: one operation
// per slab instead of two in every box test, on GPUs and PoCL alike (fma(), not mad(): PoCL's
// mad() is far slower). The boxes are padded on the host (core/accel.cpp kPad) far beyond the
// rounding in which this differs from (lo - origin) * invDir, so the hits are the same.
inline float Aabb_Enter(Ray ray, float3 invDir, float3 lo, float3 hi, float tMax) {
    float3 originInv = ray.origin * invDir;
    float3 t0 = fma(lo, invDir, -originInv), t1 = fma(hi, invDir, -originInv);
    float3 tn = Min3_Fast(t0, t1), tf = Max3_Fast(t0, t1);
    float enter = Max_Fast(Max_Fast(tn.x, tn.y), Max_Fast(tn.z, 0.0f));
    float leave = Min_Fast(Min_Fast(tf.x, tf.y), Min_Fast(tf.z, tMax));
    return enter <= leave ? enter : INFINITY;
}

// ---- one primitive: true when it becomes the hit ----
#ifdef RT_HAS_SPHERES
inline bool Hit_Sphere(const SceneData* sc, int i, Ray ray, Hit* hit) {
    global const Sphere* s = sc->spheres + i;
    float t = Sphere_Intersect(ray, f3(s->center), s->radius);
    if (!(t > 0.0f && t < hit->t)) return false;
    hit->t = t;
    hit->kind = RT_KIND_SPHERE;
    hit->object = i;
    return true;
}
#endif

#ifdef RT_HAS_TRIANGLES
// Triangle i with the given vertices (its own, or the copy a cwbvh leaf holds).
inline bool Hit_TriangleWith(float3 v0, float3 v1, float3 v2, int i, Ray ray, Hit* hit) {
    float2 uv;
    float t = Triangle_Intersect(ray, v0, v1, v2, hit->t, &uv);
    if (!(t > 0.0f && t < hit->t)) return false;
    hit->t = t;
    hit->kind = RT_KIND_TRIANGLE;
    hit->object = i;
    hit->uv = uv;
    return true;
}

// The vertices fill a Triangle's first 36 bytes. On a GPU three 16-byte loads fetch them (the
// buffer and its 80-byte records are 16-byte aligned), where the compiler fetches the 4-byte-
// aligned Float3s word by word; fewer, wider loads pay on every triangle test, shadow rays most.
// On PoCL the word loads are faster, hence the CPU branch.
inline bool Hit_Triangle(const SceneData* sc, int i, Ray ray, Hit* hit) {
#ifdef RT_DEVICE_CPU
    global const Triangle* tri = sc->triangles + i;
    return Hit_TriangleWith(f3(tri->v0), f3(tri->v1), f3(tri->v2), i, ray, hit);
#else
    global const float4* p = (global const float4*)(sc->triangles + i);
    float4 a = p[0], b = p[1], c = p[2];
    return Hit_TriangleWith(a.xyz, (float3)(a.w, b.xy), (float3)(b.zw, c.x), i, ray, hit);
#endif
}

// ---- none and bv: mesh by mesh ----
// Preliminary check (report 2.2.1): the ray misses the mesh's bounding sphere, or meets it only
// behind the origin or beyond tMax. The radius is padded on the host against rounding.
inline bool Mesh_SphereMisses(const MeshInstance* m, Ray ray, float tMax) {
    float3 oc = ray.origin - f3(m->sphereCenter);
    float r2 = m->sphereRadius * m->sphereRadius;
    float c = dot(oc, oc) - r2;
    if (c <= 0.0f) return false;  // origin inside
    float b = dot(oc, ray.dir);
    if (b > 0.0f) return true;    // outside and moving away
    float3 f = oc - b * ray.dir;  // Ray Tracing Gems ch. 7: no b^2 - c cancellation
    float disc = r2 - dot(f, f);
    return disc < 0.0f || -b - sqrt(disc) > tMax;
}

#ifdef RT_ACCEL_BV
// Kay-Kajiya slab test against the 7 slab pairs of dev::Kdop (report 3.6.2).
inline bool Kdop_Hit(global const Kdop* k, Ray ray, float tMax) {
    float3 o = ray.origin, d = ray.dir;
    float no[RT_SLABS] = {
        o.x, o.y, o.z, o.x + o.y + o.z, -o.x + o.y + o.z, o.x - o.y + o.z, o.x + o.y - o.z};
    float nd[RT_SLABS] = {
        d.x, d.y, d.z, d.x + d.y + d.z, -d.x + d.y + d.z, d.x - d.y + d.z, d.x + d.y - d.z};
    float enter = 0.0f, leave = tMax;
    for (int s = 0; s < RT_SLABS; ++s) {
        if (nd[s] == 0.0f) {
            if (no[s] < k->lo[s] || no[s] > k->hi[s]) return false;
            continue;
        }
        float inv = 1.0f / nd[s];
        float t0 = (k->lo[s] - no[s]) * inv, t1 = (k->hi[s] - no[s]) * inv;
        enter = fmax(enter, fmin(t0, t1));
        leave = fmin(leave, fmax(t0, t1));
        if (enter > leave) return false;
    }
    return true;
}
#endif

inline bool Mesh_Query(const SceneData* sc, int m, Ray ray, Hit* hit, bool anyHit) {
    MeshInstance mesh = sc->meshes[m];
    if (Mesh_SphereMisses(&mesh, ray, hit->t)) return false;
#ifdef RT_ACCEL_BV
    if (!Kdop_Hit(sc->kdops + m, ray, hit->t)) return false;
#endif
    bool found = false;
    for (int i = mesh.firstTriangle; i < mesh.firstTriangle + mesh.triangleCount; ++i) {
        if (Hit_Triangle(sc, i, ray, hit)) {
            found = true;
            if (anyHit) return true;
        }
    }
    return found;
}
#endif  // RT_HAS_TRIANGLES

// ---- grid: 3D-DDA (Amanatides and Woo 1987) ----
#ifdef RT_ACCEL_GRID
// A primitive reference of a grid cell: triangle t >= 0, sphere s as ~s.
inline bool Grid_TestRef(const SceneData* sc, int ref, Ray ray, Hit* hit) {
#ifdef RT_HAS_SPHERES
    if (ref < 0) return Hit_Sphere(sc, ~ref, ray, hit);
#endif
#ifdef RT_HAS_TRIANGLES
    if (ref >= 0) return Hit_Triangle(sc, ref, ray, hit);
#endif
    return false;
}

// Walks the cells the ray crosses in order. A hit found in a cell may lie in a later cell (the
// primitive spans both), so the walk stops only once the best hit is no farther than the
// current cell's exit: every primitive the ray meets before that point is listed in a cell
// already visited (Xiao et al. 2012 call this the in-cell test).
inline bool Grid_Query(const SceneData* sc, Ray ray, Hit* hit, bool anyHit) {
    Grid g = sc->settings.grid;
    if (g.nx == 0) return false;
    float3 inv = Ray_InvDir(ray.dir);
    float3 lo = f3(g.lo);
    float enter = Aabb_Enter(ray, inv, lo, f3(g.hi), hit->t);
    if (enter == INFINITY) return false;
    float3 p = (ray.origin + enter * ray.dir - lo) * f3(g.invCellSize);
    int cx = clamp((int)floor(p.x), 0, g.nx - 1);
    int cy = clamp((int)floor(p.y), 0, g.ny - 1);
    int cz = clamp((int)floor(p.z), 0, g.nz - 1);
    // 1 when the walk goes toward +axis (the sign of inv, which Ray_InvDir keeps nonzero).
    int sx = inv.x > 0.0f ? 1 : 0, sy = inv.y > 0.0f ? 1 : 0, sz = inv.z > 0.0f ? 1 : 0;
    bool found = false;
    for (;;) {
        // Where the ray leaves the cell through each axis's far face (from the cell index, not
        // accumulated, so that rounding does not drift along long walks).
        float tx = (lo.x + (float)(cx + sx) * g.cellSize.x - ray.origin.x) * inv.x;
        float ty = (lo.y + (float)(cy + sy) * g.cellSize.y - ray.origin.y) * inv.y;
        float tz = (lo.z + (float)(cz + sz) * g.cellSize.z - ray.origin.z) * inv.z;
        int cell = (cz * g.ny + cy) * g.nx + cx;
        int end = sc->cells[cell + 1];
        for (int k = sc->cells[cell]; k < end; ++k) {
            if (Grid_TestRef(sc, sc->cells[k], ray, hit)) {
                found = true;
                if (anyHit) return true;
            }
        }
        if (hit->t <= fmin(tx, fmin(ty, tz))) break;
        if (tx <= ty && tx <= tz) {
            cx += 2 * sx - 1;
            if (cx < 0 || cx >= g.nx) break;
        } else if (ty <= tz) {
            cy += 2 * sy - 1;
            if (cy < 0 || cy >= g.ny) break;
        } else {
            cz += 2 * sz - 1;
            if (cz < 0 || cz >= g.nz) break;
        }
    }
    return found;
}
#endif  // RT_ACCEL_GRID

// ---- BVH: stackful, nearer child first ----
#ifdef RT_ACCEL_BVH
#define RT_BVH_STACK 64  // the builder caps the depth below this (core/accel_bvh.cpp)

// A node record as two 16-byte loads. BvhNode's members are only 4-byte aligned, so a GPU
// compiler may fetch it word by word (eight loads); the buffer and its 32-byte records are
// 16-byte aligned. On PoCL it costs nothing measurable.
inline BvhNode Bvh_Load(global const BvhNode* nodes, int index) {
    global const float4* p = (global const float4*)(nodes + index);
    float4 a = p[0], b = p[1];
    BvhNode n;
    n.lo = F3(a.xyz);
    n.first = as_int(a.w);
    n.hi = F3(b.xyz);
    n.count = as_int(b.w);
    return n;
}

// The primitives of a leaf: triangles [first, first + count), or spheres [first, first - count).
inline bool Bvh_Leaf(const SceneData* sc, int first, int count, Ray ray, Hit* hit, bool anyHit) {
    bool found = false;
#ifdef RT_HAS_TRIANGLES
    for (int i = first; i < first + count; ++i)
        if (Hit_Triangle(sc, i, ray, hit)) {
            found = true;
            if (anyHit) return true;
        }
#endif
#ifdef RT_HAS_SPHERES
    for (int i = first; i < first - count; ++i)
        if (Hit_Sphere(sc, i, ray, hit)) {
            found = true;
            if (anyHit) return true;
        }
#endif
    return found;
}

// The two children of an inner node are adjacent records, so one 64-byte fetch gives both boxes
// (the layout idea of Aila and Laine 2009, kept in the binary tree the other modes and tests
// share). Once its box is tested a node is only its (first, count): the nearer child's comes
// with that fetch, and a deferred child's goes on the stack with its entry distance, so popping
// loads nothing and each step of the walk waits for one fetch.
inline bool Bvh_Query(const SceneData* sc, Ray ray, Hit* hit, bool anyHit) {
    float3 inv = Ray_InvDir(ray.dir);
    BvhNode root = Bvh_Load(sc->bvh, 0);
    if (Aabb_Enter(ray, inv, f3(root.lo), f3(root.hi), hit->t) == INFINITY) return false;
    int first = root.first, count = root.count;
    int4 stack[RT_BVH_STACK];  // first, count, entry distance (as bits) of each deferred node
    int top = 0;
    bool found = false;
    for (;;) {
        if (count == 0) {
            BvhNode a = Bvh_Load(sc->bvh, first), b = Bvh_Load(sc->bvh, first + 1);
            float ta = Aabb_Enter(ray, inv, f3(a.lo), f3(a.hi), hit->t);
            float tb = Aabb_Enter(ray, inv, f3(b.lo), f3(b.hi), hit->t);
            bool swap = tb < ta;  // ties keep the first child first
            float tNear = swap ? tb : ta, tFar = swap ? ta : tb;
            if (tNear != INFINITY) {
                if (tFar != INFINITY)
                    stack[top++] = swap ? (int4)(a.first, a.count, as_int(tFar), 0)
                                        : (int4)(b.first, b.count, as_int(tFar), 0);
                first = swap ? b.first : a.first;
                count = swap ? b.count : a.count;
                continue;
            }
        } else if (Bvh_Leaf(sc, first, count, ray, hit, anyHit)) {
            found = true;
            if (anyHit) return true;
        }
        // Next: the most recently deferred node the ray enters before the current best hit.
        int4 pending;
        do {
            if (top == 0) return found;
            pending = stack[--top];
        } while (!(as_float(pending.z) < hit->t));
        first = pending.x;
        count = pending.y;
    }
}
#endif  // RT_ACCEL_BVH

#ifdef RT_ACCEL_WIDE
#include "accel_wide.cl"
#endif

#ifdef RT_ACCEL_CWBVH
#include "accel_cwbvh.cl"
#endif

#endif
