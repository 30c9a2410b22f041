// rtlab — environment, secondary-ray origins and directions, shadows and Blinn-Phong
// (core/SHADING.md sections 3 to 9). Shared by both pipelines.
#ifndef RTLAB_CL_SHADE
#define RTLAB_CL_SHADE
#include "sampling.h"  // the shadow samples' hash, shared with the CPU reference
#include "scene.cl"
#ifdef RT_HAS_PROCEDURAL
#include "procedural.cl"
#endif

// ---- environment (section 9) ----
#ifdef RT_HAS_CUBEMAP
inline float3 Cubemap_Texel(const SceneData* sc, int face, int x, int y) {
    int n = sc->settings.cubemapSize;
    x = clamp(x, 0, n - 1);
    y = clamp(y, 0, n - 1);
    global const float* t = sc->cubemap + ((face * n + y) * n + x) * 3;
    return (float3)(t[0], t[1], t[2]);
}

inline float3 Cubemap_Lookup(const SceneData* sc, float3 d) {
    float3 a = fabs(d);
    int face;
    float sc_, tc, ma;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x >= 0.0f ? 0 : 1;
        sc_ = d.x >= 0.0f ? -d.z : d.z;
        tc = -d.y;
        ma = a.x;
    } else if (a.y >= a.z) {
        face = d.y >= 0.0f ? 2 : 3;
        sc_ = d.x;
        tc = d.y >= 0.0f ? d.z : -d.z;
        ma = a.y;
    } else {
        face = d.z >= 0.0f ? 4 : 5;
        sc_ = d.z >= 0.0f ? d.x : -d.x;
        tc = -d.y;
        ma = a.z;
    }
    float n = (float)sc->settings.cubemapSize;
    float fx = (sc_ / ma + 1.0f) * 0.5f * n - 0.5f, fy = (tc / ma + 1.0f) * 0.5f * n - 0.5f;
    float x0 = floor(fx), y0 = floor(fy);
    float tx = fx - x0, ty = fy - y0;
    int ix = (int)x0, iy = (int)y0;
    float3 top =
        Cubemap_Texel(sc, face, ix, iy) * (1.0f - tx) + Cubemap_Texel(sc, face, ix + 1, iy) * tx;
    float3 bot = Cubemap_Texel(sc, face, ix, iy + 1) * (1.0f - tx) +
                 Cubemap_Texel(sc, face, ix + 1, iy + 1) * tx;
    return top * (1.0f - ty) + bot * ty;
}
#endif

inline float3 Shade_Environment(const SceneData* sc, float3 d) {
#ifdef RT_HAS_CUBEMAP
    return Cubemap_Lookup(sc, d);
#else
    float3 horizon = f3(sc->settings.skyHorizon);
    if (d.y >= 0.0f) return horizon + (f3(sc->settings.skyZenith) - horizon) * d.y;
    return horizon + (f3(sc->settings.skyGround) - horizon) * (-d.y);
#endif
}

// ---- secondary-ray origins (section 3) ----
// Offset distance of the fixed and scaled rules. Under RT_BOUND_OFFSET only callers that have
// no hit record use it (Shade_Occlusion): a bound from |p| alone, which misses the error of
// points computed from larger coordinates (a big sphere near its top), hence Shade_PointError.
inline float Shade_Offset(float3 p) {
#if defined(RT_BOUND_OFFSET)
    float3 a = fabs(p);
    return Float_Gamma(7) * (a.x + a.y + a.z);
#elif defined(RT_SCALED_OFFSET)
    return 1e-4f * fmax(1.0f, fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))));
#else
    return 1e-4f;
#endif
}

// Per-component bound on the rounding error of a hit point of each kind, as RayTree_TraceNode
// computes it under RT_BOUND_OFFSET (SHADING.md section 3): reprojected onto the sphere
// (c + r n), reprojected onto the plane, or interpolated from the triangle's vertices.
inline float3 Shade_SphereError(float3 center, float radius, float3 n) {
    return Float_Gamma(5) * (fabs(center) + radius * fabs(n));
}

inline float3 Shade_PlaneError(float3 p, float offset) {
    return Float_Gamma(6) * (fabs(p) + fabs(offset));
}

inline float3 Shade_TriangleError(float3 v0, float3 v1, float3 v2) {
    return Float_Gamma(7) * (fabs(v0) + fabs(v1) + fabs(v2));
}

// pbrt-v4's OffsetRayOrigin: from p, whose components are off by at most err, move along the
// geometric normal ng (side +1) or against it (-1) by dot(|ng|, err), which leaves the box of
// possible true points on that side of the surface; then round each component one float away
// from p, so that the addition cannot round the offset back into the box.
inline float3 Shade_SpawnOrigin(float3 p, float3 ng, float3 err, float side) {
    float3 w = side * ng;
    float3 o = p + dot(fabs(ng), err) * w;
    o.x = w.x > 0.0f ? nextafter(o.x, INFINITY) : (w.x < 0.0f ? nextafter(o.x, -INFINITY) : o.x);
    o.y = w.y > 0.0f ? nextafter(o.y, INFINITY) : (w.y < 0.0f ? nextafter(o.y, -INFINITY) : o.y);
    o.z = w.z > 0.0f ? nextafter(o.z, INFINITY) : (w.z < 0.0f ? nextafter(o.z, -INFINITY) : o.z);
    return o;
}

// ---- secondary-ray directions (sections 6, 7) ----
inline float3 Shade_Reflect(float3 d, float3 n) { return d - 2.0f * n * dot(d, n); }

// Report Algorithm 1 with the S > 1 test; n faces the incoming ray, eta = n1/n2.
inline bool Shade_Refract(float3 d, float3 n, float eta, float3* t) {
    float c = -dot(n, d);
    float s = eta * eta * (1.0f - c * c);
    if (s > 1.0f) return false;  // total internal reflection
    *t = eta * d + (eta * c - sqrt(1.0f - s)) * n;
    return true;
}

// Report Algorithm 5 with sinT = (n1/n2) sqrt(1 - cos^2); 1 under total internal reflection.
inline float Shade_Fresnel(float cosI, float n1, float n2) {
    float sinT = n1 / n2 * sqrt(fmax(0.0f, 1.0f - cosI * cosI));
    if (sinT >= 1.0f) return 1.0f;
    float cosT = sqrt(1.0f - sinT * sinT);
    float rs = (n2 * cosI - n1 * cosT) / (n2 * cosI + n1 * cosT);
    float rp = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    return (rs * rs + rp * rp) / 2.0f;
}

// ---- shadows (section 4) ----
inline int Shade_LightSamples(const SceneData* sc, int j) {
    return sc->lights[j].radius > 0.0f ? sc->settings.shadowSamples : 1;
}

// Where the shadow samples of light j lie as seen from hit point p with shading normal n:
// one per ring of equal area of the light's disk, jittered, at golden-angle steps from a
// rotation (core/sampling.h; core/reference.cpp does the same in double). key: the shading
// point's sampler key (Sampling_PointKey of its pixel, AA sample and depth).
typedef struct LightSamples {
    float3 center, t, bt;  // the light's position and a basis of its disk facing p
    float radius, turn;
    int count;  // 0 when the light is behind the surface
} LightSamples;

RT_INLINE LightSamples Shade_LightSamplesFrom(const SceneData* sc, float3 p, float3 n, int j,
                                              uint key) {
    Light light = sc->lights[j];
    LightSamples s;
    s.center = f3(light.position);
    s.radius = light.radius;
    float3 w = normalize(s.center - p);
    s.count = 0;
    if (dot(n, w) <= 0.0f) return s;  // the other fields are not used then
    s.count = Shade_LightSamples(sc, j);
    // Orthonormal basis around w (Duff et al. 2017).
    float sign = w.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + w.z);
    float b = w.x * w.y * a;
    s.t = (float3)(1.0f + sign * w.x * w.x * a, sign * b, -sign * w.x);
    s.bt = (float3)(b, sign + w.y * w.y * a, -w.y);
    s.turn = Sampling_Unit(key, j, 0, 0);
    return s;
}

// Sample k of light j (LightSamples).
RT_INLINE float3 Shade_LightPoint(const LightSamples* s, uint key, int j, int k) {
    float3 q = s->center;
    if (s->radius > 0.0f) {
        float area = ((float)k + Sampling_Unit(key, j, k, 1)) / (float)s->count;
        float rho = s->radius * sqrt(area);
        float phi = 2.399963229728653f * (float)k + 6.283185307179586f * s->turn;
        q = s->center + rho * (cos(phi) * s->t + sin(phi) * s->bt);
    }
    return q;
}

// Occluded shadow rays toward light j from `origin`, the offset start of hit point p with
// shading normal n; 0 when the light is behind the surface. key: as Shade_LightSamplesFrom.
RT_INLINE int Shade_OcclusionFrom(const SceneData* sc, float3 p, float3 n, float3 origin, int j,
                                  uint key) {
    LightSamples s = Shade_LightSamplesFrom(sc, p, n, j, key);
    int occluded = 0;
    for (int k = 0; k < s.count; ++k) {
        float3 v = Shade_LightPoint(&s, key, j, k) - origin;
        float len = length(v);
        RT_COUNT_RAY(sc, RT_RAY_SHADOW);
        if (Scene_Occluded(sc, makeRay(origin, v / len), len)) ++occluded;
    }
    return occluded;
}

// The same from p itself, offset by Shade_Offset(p) along n; RayTree_TraceNode uses the hit's
// own error bound instead (RayTree_SpawnOrigin).
inline int Shade_Occlusion(const SceneData* sc, float3 p, float3 n, int j, uint key) {
    return Shade_OcclusionFrom(sc, p, n, p + Shade_Offset(p) * n, j, key);
}

// ---- Blinn-Phong (section 5) ----
// `pattern`: the material's RT_PATTERN_* when the caller knows it (a constant in a kernel that
// shades one pattern only, so that the others' code drops out), or RT_PATTERN_ANY: read it.
inline float3 Shade_BaseOf(const SceneData* sc, const Node* node, int pattern) {
    Material m = sc->materials[node->material];
    float3 p = f3(node->point), n = f3(node->normal), d = f3(node->dir);
    float3 diffuse = f3(m.diffuse);
#ifdef RT_HAS_PROCEDURAL
    if (pattern == RT_PATTERN_ANY) pattern = m.pattern;
    if (pattern != RT_PATTERN_NONE) Procedural_Apply(&m, pattern, p, &diffuse, &n);
#endif
    float3 c = f3(m.ambient);
    for (int j = 0; j < sc->settings.lightCount; ++j) {
        Light light = sc->lights[j];
        float3 l = normalize(f3(light.position) - p);
        float ndl = dot(n, l);
        if (ndl <= 0.0f) continue;
        float vis = 1.0f - sc->settings.shadowStrength * (float)node->occluded[j] /
                               (float)Shade_LightSamples(sc, j);
        float3 h = normalize(l - d);
        float spec = pow(fmax(dot(n, h), 0.0f), m.exponent);
        c += vis * f3(light.color) * (diffuse * ndl + f3(m.specular) * spec);
    }
    return c;
}

inline float3 Shade_Base(const SceneData* sc, const Node* node) {
    return Shade_BaseOf(sc, node, RT_PATTERN_ANY);
}

#endif
