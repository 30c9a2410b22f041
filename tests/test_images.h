// rtlab tests — image comparisons that several test files share.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/image.h"

namespace rt::test {

// The same size and the same bits in every channel of every pixel.
inline bool sameBits(const Image& a, const Image& b) {
    return a.rgb.size() == b.rgb.size() &&
           std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

// Pixels whose clamped linear value differs by more than 2/255 in some channel (the acne rate's
// count, core/SHADING.md section 3).
inline int pixelsOff(const Image& a, const Image& b) {
    int n = 0;
    for (size_t p = 0; p < a.rgb.size() / 3; ++p) {
        bool off = false;
        for (int c = 0; c < 3; ++c) {
            const float x = std::clamp(a.rgb[p * 3 + c], 0.f, 1.f),
                        y = std::clamp(b.rgb[p * 3 + c], 0.f, 1.f);
            off = off || !(std::abs(x - y) <= 2.f / 255.f);
        }
        n += off;
    }
    return n;
}

}  // namespace rt::test
