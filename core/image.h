// rtlab — a linear RGB float image. Core code only produces and consumes these; reading and
// writing files is the job of rtlab_image (image/), which wraps OpenImageIO.
#pragma once

#include <cstddef>
#include <vector>

namespace rt {

struct Image {
    int width = 0, height = 0;
    std::vector<float> rgb;  // row-major, top row first, 3 floats per pixel, linear radiance

    Image() = default;
    Image(int w, int h) : width(w), height(h), rgb(std::size_t(w) * h * 3, 0.f) {}
    float* pixel(int x, int y) { return &rgb[(std::size_t(y) * width + x) * 3]; }
    const float* pixel(int x, int y) const { return &rgb[(std::size_t(y) * width + x) * 3]; }
};

}  // namespace rt
