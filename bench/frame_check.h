// rtlab bench — what a frame must satisfy whatever the scene, and how two frames of one setting
// compare: for the sweeps' limits groups (pipelines must agree at a limit) and the GPU smoke
// check. rtlab-bench links no OpenImageIO (it travels to GPU hosts without it), so these few
// loops stand in for image/compare.h there.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/image.h"

namespace rt::bench {

// Pixels with a channel that is NaN or infinite: never right, whatever the scene.
inline long long nonFinitePixels(const Image& image) {
    long long bad = 0;
    for (size_t i = 0; i + 2 < image.rgb.size(); i += 3)
        if (!std::isfinite(image.rgb[i]) || !std::isfinite(image.rgb[i + 1]) ||
            !std::isfinite(image.rgb[i + 2]))
            ++bad;
    return bad;
}

// Two frames of one size, channel by channel; NaN in both at one place counts as equal, in one
// only as infinitely far.
struct FrameAgreement {
    bool sameSize = false;
    double maxAbs = 0;          // the largest |difference|
    double meanAbs = 0;         // over every channel
    double fractionWithin = 0;  // pixels whose channels all differ by at most `tolerance`
};

inline FrameAgreement compareFrames(const Image& a, const Image& b, double tolerance) {
    FrameAgreement r;
    if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) return r;
    r.sameSize = true;
    double sum = 0;
    size_t within = 0;
    for (size_t i = 0; i + 2 < a.rgb.size(); i += 3) {
        double worst = 0;
        for (size_t c = i; c < i + 3; ++c) {
            float x = a.rgb[c], y = b.rgb[c];
            double d = std::isnan(x) || std::isnan(y)
                           ? (std::isnan(x) == std::isnan(y) ? 0 : INFINITY)
                       : x == y ? 0.0
                                : std::fabs(double(x) - double(y));
            worst = std::max(worst, d);
            sum += std::isfinite(d) ? d : 0;
        }
        r.maxAbs = std::max(r.maxAbs, worst);
        within += worst <= tolerance;
    }
    size_t pixels = a.rgb.size() / 3;
    r.meanAbs = a.rgb.empty() ? 0 : sum / double(a.rgb.size());
    r.fractionWithin = pixels ? double(within) / double(pixels) : 1;
    return r;
}

}  // namespace rt::bench
