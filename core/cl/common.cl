// rtlab — basics every kernel file includes: the shared records, Float3 <-> float3, the ray.
//
// FP_CONTRACT OFF: the compiler must not fuse a*b+c into an fma in one kernel and not in another;
// every pipeline calls the same functions, and they must round identically.
#pragma OPENCL FP_CONTRACT OFF
#ifndef RTLAB_CL_COMMON
#define RTLAB_CL_COMMON

#include "types.h"

// A helper that PoCL must inline. Its inliner leaves some large helpers with one caller as calls
// (a private struct then lives in memory): RayTree_Surface and the light samples, split out
// of their callers, slowed the megakernel on every scene until they were forced inline. GPU
// compilers inline them anyway.
#ifdef RT_DEVICE_CPU
#define RT_INLINE __attribute__((always_inline)) inline
#else
#define RT_INLINE inline
#endif

// The stage functions the register-pressure study (scripts/register-study) keeps out of line,
// one at a time: built with -DRT_OUTLINE_QUERY (the traversal, Scene_Query), _SURFACE
// (RayTree_Surface), _SHADOWS (RayTree_CastShadows), _STEP (PathState_Step: shading and the
// children's rays) or _PATTERN (Procedural_Apply), that function is a call instead of being
// inlined, and its kernel's register count shows what inlining it cost. Without them, as before.
#define RT_OUTLINE __attribute__((noinline))
#ifdef RT_OUTLINE_QUERY
#define RT_QUERY_LINKAGE RT_OUTLINE
#else
#define RT_QUERY_LINKAGE inline
#endif
#ifdef RT_OUTLINE_SURFACE
#define RT_SURFACE_LINKAGE RT_OUTLINE
#else
#define RT_SURFACE_LINKAGE RT_INLINE
#endif
#ifdef RT_OUTLINE_SHADOWS
#define RT_SHADOWS_LINKAGE RT_OUTLINE
#else
#define RT_SHADOWS_LINKAGE RT_INLINE
#endif
#ifdef RT_OUTLINE_STEP
#define RT_STEP_LINKAGE RT_OUTLINE
#else
#define RT_STEP_LINKAGE inline
#endif
#ifdef RT_OUTLINE_PATTERN
#define RT_PATTERN_LINKAGE RT_OUTLINE
#else
#define RT_PATTERN_LINKAGE inline
#endif

inline float3 f3(Float3 v) { return (float3)(v.x, v.y, v.z); }

inline Float3 F3(float3 v) {
    Float3 r;
    r.x = v.x;
    r.y = v.y;
    r.z = v.z;
    return r;
}

// gamma(n) = n u / (1 - n u) with u = 2^-24: the relative error bound of n float operations
// (Higham; pbrt-v4's error analysis uses the same). The spawn offsets (shade.cl) and the
// intersectors' conservative t > 0 tests (intersect.cl) are built from it.
inline float Float_Gamma(int n) {
    float nu = (float)n * 5.9604645e-8f;
    return nu / (1.0f - nu);
}

inline float component(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

typedef struct Ray {
    float3 origin;
    float3 dir;  // unit length
} Ray;

inline Ray makeRay(float3 origin, float3 dir) {
    Ray r;
    r.origin = origin;
    r.dir = dir;
    return r;
}

#endif
