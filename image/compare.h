// rtlab — image comparison through OpenImageIO (ImageBufAlgo::compare), on linear values clamped
// to [0, 1] as core/SHADING.md section 10 specifies. Non-finite values are counted before any
// clamp (a clamp turns NaN into 0 and +Inf into 1, which would hide a broken frame) and fail the
// comparison: such a pixel is over any tolerance and makes every error figure infinite.
#pragma once

#include "core/image.h"

namespace rt {

struct ImageDiff {
    double meanAbs = 0;  // mean absolute difference over all channels
    double maxAbs = 0;   // largest absolute difference of any channel
    double rmse = 0;
    double fractionWithin = 1;  // fraction of pixels whose channels all lie within tolerance
    long long pixelsOver = 0;   // pixels with some channel above tolerance (or non-finite)
    long long nonfinite = 0;    // pixels with a NaN or infinite channel, in either image
    // True when both images are finite everywhere and every pixel is within tolerance.
    bool allWithin() const { return nonfinite == 0 && pixelsOver == 0; }
};

// Pixels with a NaN or infinite channel, counted by OpenImageIO on the raw floats.
long long countNonFinite(const Image& image);

// Throws rt::Error when the sizes differ. clampToUnit = false compares raw floats (EXR checks).
ImageDiff compareImages(const Image& a, const Image& b, double tolerance, bool clampToUnit = true);

}  // namespace rt
