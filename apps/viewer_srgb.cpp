// rtlab-view — sRGB quantisation through a threshold table: byte k is the number of thresholds
// at or below the value, where threshold k is the smallest float that image_io.cpp's
// lround(encode(v) * 255) maps to k or more. Eight comparisons per channel instead of a pow().
#include "apps/viewer_srgb.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>

namespace rt::view {
namespace {

// core/SHADING.md section 10, as image/image_io.cpp writes it.
double srgbEncode(double c) {
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
}
double srgbDecode(double s) {
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

int byteOf(float v) {
    double c = std::isnan(v) ? 0.0 : std::clamp(double(v), 0.0, 1.0);
    return int(std::lround(srgbEncode(c) * 255));
}

struct Tables {
    std::array<float, 256> threshold{};  // [0] unused
    std::array<float, 256> decode{};
};

Tables buildTables() {
    Tables t;
    // Non-negative floats order like their bit patterns, so bisect on the bits in [0, 1].
    for (int k = 1; k < 256; ++k) {
        uint32_t lo = 0, hi = std::bit_cast<uint32_t>(1.0f);
        while (lo < hi) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (byteOf(std::bit_cast<float>(mid)) >= k)
                hi = mid;
            else
                lo = mid + 1;
        }
        t.threshold[k] = std::bit_cast<float>(lo);
    }
    for (int k = 0; k < 256; ++k) {
        float v = float(srgbDecode(k / 255.0));
        // float rounding may land a hair across a threshold; the threshold itself is exact.
        t.decode[k] = byteOf(v) == k ? v : (k ? t.threshold[k] : 0.f);
    }
    return t;
}

const Tables& tables() {
    static const Tables t = buildTables();
    return t;
}

}  // namespace

void encodeSrgb8(const Image& image, std::vector<uint8_t>& rgb) {
    const auto& th = tables().threshold;
    rgb.resize(image.rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) {
        float v = image.rgb[i];
        if (!(v > 0.f)) {  // also NaN
            rgb[i] = 0;
            continue;
        }
        rgb[i] = uint8_t(std::upper_bound(th.begin() + 1, th.end(), v) - (th.begin() + 1));
    }
}

Image decodeSrgb8(const std::vector<uint8_t>& rgb, int width, int height) {
    const auto& dec = tables().decode;
    Image image(width, height);
    for (size_t i = 0; i < image.rgb.size() && i < rgb.size(); ++i) image.rgb[i] = dec[rgb[i]];
    return image;
}

}  // namespace rt::view
