// rtlab — ray/primitive tests (core/SHADING.md section 2). Each returns the hit distance t > 0,
// or -1 for a miss. The plain methods are the report's; the robust ones are behind defines.
// Every test accepts a t only when it is positive beyond its own rounding error (pbrt-v4's
// conservative t > 0, SHADING.md section 3): a ray that leaves a surface cannot hit that surface
// again at a t whose sign the float arithmetic cannot tell, which is what speckled large
// triangles (issue 51) whatever the origin's offset.
#ifndef RTLAB_CL_INTERSECT
#define RTLAB_CL_INTERSECT
#include "common.cl"

#define RT_MISS (-1.0f)

// Report Algorithm 2 (RT_ROBUST_SPHERE unset) or Ray Tracing Gems ch. 7 (set). Both start with the
// preliminary "sphere is behind the ray" check of section 2.2.1.
inline float Sphere_Intersect(Ray ray, float3 center, float radius) {
    float3 oc = ray.origin - center;
    float c = dot(oc, oc) - radius * radius;
    float bd = dot(ray.dir, oc);
    if (c > 0.0f && bd > 0.0f) return RT_MISS;  // origin outside and moving away
#ifdef RT_ROBUST_SPHERE
    float b = -bd;
    float3 f = oc + b * ray.dir;
    float disc = radius * radius - dot(f, f);
    if (disc < 0.0f) return RT_MISS;
    float q = b + (b >= 0.0f ? sqrt(disc) : -sqrt(disc));
    // c / q is the root that can be near 0 (a ray leaving the sphere): c carries an absolute
    // error of gamma(6) (|oc|^2 + r^2), so c / q is trusted only past that over |q|. q has no
    // cancellation: its sign is exact.
    // (c / q > bound / |q| without the division.)
    float tc = c / q, tq = q;
    bool okc = (q > 0.0f ? c : -c) > Float_Gamma(8) * (c + 2.0f * radius * radius);
    bool okq = tq > 0.0f;
    if (okc && okq) return fmin(tc, tq);
    return okc ? tc : (okq ? tq : RT_MISS);
#else
    float b = 2.0f * bd;
    float disc = b * b - 4.0f * c;
    if (disc < 0.0f) return RT_MISS;
    float s = sqrt(disc);
    float t0 = (-b - s) / 2.0f, t1 = (-b + s) / 2.0f;
    // One of -b -/+ s cancels; its error is that of s, the discriminant's over 2 s: a root t
    // needs t > dt / s (compared as t s > dt, without the division).
    float dt = Float_Gamma(13) * (b * b + 4.0f * (c + 2.0f * radius * radius));
    return t0 * s > dt ? t0 : (t1 * s > dt ? t1 : RT_MISS);
#endif
}

inline float Plane_Intersect(Ray ray, float3 normal, float offset) {
    float den = dot(normal, ray.dir);
    if (den == 0.0f) return RT_MISS;
    float num = offset - dot(normal, ray.origin);
    // num is off by up to gamma(4) (|offset| + |n|.|o|): inside that the origin is on the plane.
    if (!(fabs(num) > Float_Gamma(4) * (fabs(offset) + dot(fabs(normal), fabs(ray.origin)))))
        return RT_MISS;
    float t = num / den;
    return t > 0.0f ? t : RT_MISS;
}

#ifdef RT_HAS_TRIANGLES  // a scene without triangles compiles no triangle code at all
// Barycentrics: p = (1 - u - v) v0 + u v1 + v v2.
#ifndef RT_WATERTIGHT
// A bound on the error of Moller-Trumbore's t = f e2.(s x e1): s = o - v0 and e1 carry an ulp,
// each component of q = s x e1 gamma(4) of Q = |s| x |e1| (the cross product with + for -),
// their dot with e2 gamma(8) of |e2|.Q; the factor f only scales it.
#define RT_DEFINE_MT_DELTA_T(NAME, T)                                                            \
    inline T NAME(T sx, T sy, T sz, float3 e1, float3 e2, T f) {                                 \
        T qx = fabs(sy) * fabs(e1.z) + fabs(sz) * fabs(e1.y);                                    \
        T qy = fabs(sz) * fabs(e1.x) + fabs(sx) * fabs(e1.z);                                    \
        T qz = fabs(sx) * fabs(e1.y) + fabs(sy) * fabs(e1.x);                                    \
        return Float_Gamma(9) * fabs(f) * (fabs(e2.x) * qx + fabs(e2.y) * qy + fabs(e2.z) * qz); \
    }
RT_DEFINE_MT_DELTA_T(Triangle_MollerTrumboreDeltaTs, float)
inline float Triangle_MollerTrumboreDeltaT(float3 s, float3 e1, float3 e2, float f) {
    return Triangle_MollerTrumboreDeltaTs(s.x, s.y, s.z, e1, e2, f);
}

// Report Algorithm 3 (Moller-Trumbore) with a = edge1.h and the u + v > 1 test.
inline float Triangle_Intersect(Ray ray, float3 v0, float3 v1, float3 v2, float tMax, float2* uv) {
    float3 e1 = v1 - v0, e2 = v2 - v0;
    float3 h = cross(ray.dir, e2);
    float a = dot(e1, h);
    if (a == 0.0f) return RT_MISS;
    float f = 1.0f / a;
    float3 s = ray.origin - v0;
    float u = f * dot(s, h);
    if (u < 0.0f || u > 1.0f) return RT_MISS;
    float3 q = cross(s, e1);
    float v = f * dot(ray.dir, q);
    if (v < 0.0f || u + v > 1.0f) return RT_MISS;
    float t = f * dot(e2, q);
    // The bound only for a hit that would count: nearer than the caller's tMax.
    if (!(t < tMax) || t <= Triangle_MollerTrumboreDeltaT(s, e1, e2, f)) return RT_MISS;
    *uv = (float2)(u, v);
    return t;
}
#else
// pbrt-v4's conservative bound on the error of the watertight test's t (Pharr, Jakob and
// Humphreys, 4th ed., section 6.8.7): from the sheared vertices (x, y), their z scaled by sz
// (z) and the edge functions U, V, W. A t at or below it may be the rounding of t <= 0.
#define RT_DEFINE_WATERTIGHT_DELTA_T(NAME, T)                                                     \
    inline T NAME(T ax, T ay, T az, T bx, T by, T bz, T cx, T cy, T cz, T U, T V, T W, T rcp) {   \
        T maxZ = fmax(fabs(az), fmax(fabs(bz), fabs(cz)));                                        \
        T maxX = fmax(fabs(ax), fmax(fabs(bx), fabs(cx)));                                        \
        T maxY = fmax(fabs(ay), fmax(fabs(by), fabs(cy)));                                        \
        T deltaZ = Float_Gamma(3) * maxZ;                                                         \
        T deltaX = Float_Gamma(5) * (maxX + maxZ), deltaY = Float_Gamma(5) * (maxY + maxZ);       \
        T deltaE = 2.0f * (Float_Gamma(2) * maxX * maxY + deltaY * maxX + deltaX * maxY);         \
        T maxE = fmax(fabs(U), fmax(fabs(V), fabs(W)));                                           \
        return 3.0f * (Float_Gamma(3) * maxE * maxZ + deltaE * maxZ + deltaZ * maxE) * fabs(rcp); \
    }
RT_DEFINE_WATERTIGHT_DELTA_T(Triangle_WatertightDeltaT, float)

// Woop, Benthin, Wald 2013: shear into ray space, exact edge-function signs. A ray through a
// shared edge cannot slip between the two triangles (no double-precision fallback here).
inline float Triangle_Intersect(Ray ray, float3 v0, float3 v1, float3 v2, float tMax, float2* uv) {
    float3 ad = fabs(ray.dir);
    int kz = ad.x >= ad.y ? (ad.x >= ad.z ? 0 : 2) : (ad.y >= ad.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    float dz = component(ray.dir, kz);
    if (dz < 0.0f) {
        int tmp = kx;
        kx = ky;
        ky = tmp;
    }
    float sx = component(ray.dir, kx) / dz, sy = component(ray.dir, ky) / dz, sz = 1.0f / dz;
    float3 A = v0 - ray.origin, B = v1 - ray.origin, C = v2 - ray.origin;
    float ax = component(A, kx) - sx * component(A, kz),
          ay = component(A, ky) - sy * component(A, kz);
    float bx = component(B, kx) - sx * component(B, kz),
          by = component(B, ky) - sy * component(B, kz);
    float cx = component(C, kx) - sx * component(C, kz),
          cy = component(C, ky) - sy * component(C, kz);
    float U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return RT_MISS;
    float det = U + V + W;
    if (det == 0.0f) return RT_MISS;
    float T = U * sz * component(A, kz) + V * sz * component(B, kz) + W * sz * component(C, kz);
    if ((det < 0.0f && T >= 0.0f) || (det > 0.0f && T <= 0.0f)) return RT_MISS;
    float rcp = 1.0f / det;
    float t = T * rcp;
    // The bound only for a hit that would count: nearer than the caller's tMax.
    if (!(t < tMax)) return RT_MISS;
    if (t <= Triangle_WatertightDeltaT(ax, ay, sz * component(A, kz), bx, by, sz * component(B, kz),
                                       cx, cy, sz * component(C, kz), U, V, W, rcp))
        return RT_MISS;
    *uv = (float2)(V * rcp, W * rcp);
    return t;
}
#endif
#endif  // RT_HAS_TRIANGLES

#endif
