// rtlab tests — image comparisons that several test files share.
#pragma once

#include <cstring>

#include "core/image.h"

namespace rt::test {

// The same size and the same bits in every channel of every pixel.
inline bool sameBits(const Image& a, const Image& b) {
    return a.rgb.size() == b.rgb.size() &&
           std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

}  // namespace rt::test
