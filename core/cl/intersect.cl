// rtlab — ray/primitive tests (core/SHADING.md section 2). Each returns the hit distance t > 0,
// or -1 for a miss. The plain methods are the report's; the robust ones are behind defines.
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
    float t0 = c / q, t1 = q;
    if (t0 > t1) {
        float tmp = t0;
        t0 = t1;
        t1 = tmp;
    }
#else
    float b = 2.0f * bd;
    float disc = b * b - 4.0f * c;
    if (disc < 0.0f) return RT_MISS;
    float s = sqrt(disc);
    float t0 = (-b - s) / 2.0f, t1 = (-b + s) / 2.0f;
#endif
    return t0 > 0.0f ? t0 : (t1 > 0.0f ? t1 : RT_MISS);
}

inline float Plane_Intersect(Ray ray, float3 normal, float offset) {
    float den = dot(normal, ray.dir);
    if (den == 0.0f) return RT_MISS;
    float t = (offset - dot(normal, ray.origin)) / den;
    return t > 0.0f ? t : RT_MISS;
}

#ifdef RT_HAS_TRIANGLES  // a scene without triangles compiles no triangle code at all
// Barycentrics: p = (1 - u - v) v0 + u v1 + v v2.
#ifndef RT_WATERTIGHT
// Report Algorithm 3 (Moller-Trumbore) with a = edge1.h and the u + v > 1 test.
inline float Triangle_Intersect(Ray ray, float3 v0, float3 v1, float3 v2, float2* uv) {
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
    if (t <= 0.0f) return RT_MISS;
    *uv = (float2)(u, v);
    return t;
}
#else
// Woop, Benthin, Wald 2013: shear into ray space, exact edge-function signs. A ray through a
// shared edge cannot slip between the two triangles (no double-precision fallback here).
inline float Triangle_Intersect(Ray ray, float3 v0, float3 v1, float3 v2, float2* uv) {
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
    *uv = (float2)(V * rcp, W * rcp);
    return T * rcp;
}
#endif
#endif  // RT_HAS_TRIANGLES

#endif
