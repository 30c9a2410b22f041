// rtlab — the soft-shadow sampler, shared by the host (C++20) and the device (OpenCL C 1.2).
//
// A light of radius r > 0 is sampled at n points of its disk. Point k lies in the k-th of n
// rings of equal area (radius r sqrt((k + u) / n), u jittered in [0, 1)) at angle golden * k
// plus a rotation of the whole pattern: every ring holds exactly one point (stratified), and
// the golden angle spreads the points around the disk. The jitter u and the rotation come from
// an integer hash of what every pipeline and the CPU reference know exactly: the pixel, the AA
// sample, the ray's depth, the light and k. Hit positions are not used: they differ between the
// float pipelines and the double reference. With one fixed pattern for every pixel a penumbra
// shows concentric bands (every pixel misses the same parts of the light); jittered per pixel, the
// same error is spread as fine noise that averages out.
//
// Only integer work and the exact conversion to [0, 1) live here; each side maps the result
// onto the disk in its own precision (core/cl/shade.cl in float, core/reference.cpp in double).
#ifndef RTLAB_CORE_SAMPLING_H
#define RTLAB_CORE_SAMPLING_H

#include "types.h"

RT_DEV_BEGIN

// The golden angle, 2 pi (1 - 1 / phi), in radians.
#define RT_GOLDEN_ANGLE 2.399963229728653
#define RT_TWO_PI 6.283185307179586

// PCG-based 32-bit integer hash (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering").
inline uint32_t Sampling_Hash(uint32_t v) {
    uint32_t state = v * 747796405u + 2891336453u;
    uint32_t word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The key of one shading point: pixel (x, y), AA sample index, depth in the ray tree.
inline uint32_t Sampling_PointKey(int32_t x, int32_t y, int32_t sample, int32_t depth) {
    uint32_t h = Sampling_Hash((uint32_t)depth);
    h = Sampling_Hash((uint32_t)sample ^ h);
    h = Sampling_Hash((uint32_t)y ^ h);
    return Sampling_Hash((uint32_t)x ^ h);
}

// A number in [0, 1) for dimension `dim` of shadow sample k toward light j (k < 256, dim < 2).
// 24 bits times 2^-24: exact in float and double alike.
inline float Sampling_Unit(uint32_t key, int32_t light, int32_t k, int32_t dim) {
    uint32_t index = ((uint32_t)light * 256u + (uint32_t)k) * 2u + (uint32_t)dim;
    return (float)(Sampling_Hash(key ^ Sampling_Hash(index)) >> 8) * (1.0f / 16777216.0f);
}

RT_DEV_END

#ifndef __OPENCL_C_VERSION__
#include <cmath>
namespace rt {
// Shadow sample k of n toward light j (n <= 256), in double precision (the CPU reference and the
// tests); Shade_OcclusionFrom computes the same in float. Dimension 1 of k jitters its ring;
// dimension 0 of k = 0 rotates the whole pattern.
struct DiskSample {
    double radius;  // as a fraction of the light's radius
    double angle;   // radians
};
inline DiskSample shadowDiskSample(uint32_t key, int light, int k, int n) {
    const double area = (k + double(dev::Sampling_Unit(key, light, k, 1))) / n;
    const double turn = double(dev::Sampling_Unit(key, light, 0, 0));
    return {std::sqrt(area), RT_GOLDEN_ANGLE * k + RT_TWO_PI * turn};
}
}  // namespace rt
#endif

#endif
