// rtlab — the 8-bit child boxes of the wide BVHs (core/accel_wide.cpp, core/accel_cwbvh.cpp;
// Ylitie, Karras and Laine 2017): a node's box is origin + [0, 255] * step per axis, step a
// power of two 2^(e - 127) that the device decodes from the exponent byte with a shift, and each
// child's bounds are rounded outward so that the decoded box always holds the child's exact one.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "core/types.h"

namespace rt::quant {

// 2^(e - 127), from a float's exponent bits: what the device computes with a shift.
inline float stepOf(uint8_t e) { return std::bit_cast<float>(uint32_t(e) << 23); }

// The smallest exponent whose 255 steps from lo reach hi, in the device's float arithmetic.
inline uint8_t exponentFor(float lo, float hi) {
    int e = 1;  // 0 would be a zero step
    if (hi > lo) {
        int x;
        std::frexp((hi - lo) / 255.f, &x);
        e = std::max(1, x + 125);  // one below the estimate; the loop climbs to the exact one
    }
    while (e < 254 && lo + 255.f * stepOf(uint8_t(e)) < hi) ++e;
    return uint8_t(e);
}

// Outward rounding: the decoded bound origin + q * step never cuts into the child's box.
inline uint8_t quantLo(float origin, float step, float v) {
    int q = std::clamp(int(std::floor((v - origin) / step)), 0, 255);
    while (q > 0 && origin + float(q) * step > v) --q;
    return uint8_t(q);
}
inline uint8_t quantHi(float origin, float step, float v) {
    int q = std::clamp(int(std::ceil((v - origin) / step)), 0, 255);
    while (q < 255 && origin + float(q) * step < v) ++q;
    return uint8_t(q);
}

// Surface area (halved) of a binary node's box: the collapse opens the largest child first.
inline float area(const dev::BvhNode& n) {
    float dx = n.hi.x - n.lo.x, dy = n.hi.y - n.lo.y, dz = n.hi.z - n.lo.z;
    return dx * dy + dy * dz + dz * dx;
}

// An axis-aligned box, decoded or exact, for the checkers.
struct Box {
    float lo[3], hi[3];
};

inline bool contains(const Box& b, const float* lo, const float* hi) {
    for (int a = 0; a < 3; ++a)
        if (lo[a] < b.lo[a] || hi[a] > b.hi[a]) return false;
    return true;
}

inline Box sphereBox(const dev::Sphere& s) {
    const float* c = &s.center.x;
    return {{c[0] - s.radius, c[1] - s.radius, c[2] - s.radius},
            {c[0] + s.radius, c[1] + s.radius, c[2] + s.radius}};
}

inline Box triangleBox(const dev::Triangle& t) {
    Box b;
    for (int a = 0; a < 3; ++a) {
        float v0 = (&t.v0.x)[a], v1 = (&t.v1.x)[a], v2 = (&t.v2.x)[a];
        b.lo[a] = std::min({v0, v1, v2});
        b.hi[a] = std::max({v0, v1, v2});
    }
    return b;
}

}  // namespace rt::quant
