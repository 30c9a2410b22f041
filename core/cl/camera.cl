// rtlab — primary rays (core/SHADING.md section 1, report eq. 12).
#ifndef RTLAB_CL_CAMERA
#define RTLAB_CL_CAMERA
#include "common.cl"

// Sub-pixel offset of sample `index` of an n x n grid, sy outer and sx inner.
inline float2 Camera_SampleOffset(int index, int n) {
    int sy = index / n, sx = index - sy * n;
    return (float2)(((float)sx + 0.5f) / (float)n, ((float)sy + 0.5f) / (float)n);
}

inline Ray Camera_PrimaryRay(const RenderSettings* s, int x, int y, float2 offset) {
    float W = (float)s->width, H = (float)s->height;
    float D = 1.0f / tan(s->camera.fovY * 0.5f);
    float3 nc = (float3)((2.0f * ((float)x + offset.x) / W - 1.0f) * (W / H),
                         1.0f - 2.0f * ((float)y + offset.y) / H, D);
    float ca = cos(s->camera.pitch), sa = sin(s->camera.pitch);
    float3 o = (float3)(nc.x, nc.y * ca + nc.z * sa, nc.z * ca - nc.y * sa);
    float cb = cos(s->camera.yaw), sb = sin(s->camera.yaw);
    float3 d = (float3)(o.x * cb + o.z * sb, o.y, o.z * cb - o.x * sb);
    return makeRay(f3(s->camera.position), normalize(d));
}

#endif
