// rtlab — image comparison through OpenImageIO (ImageBufAlgo::compare), on linear values clamped
// to [0, 1] as core/SHADING.md section 10 specifies.
#pragma once

#include "core/image.h"

namespace rt {

struct ImageDiff {
    double meanAbs = 0;          // mean absolute difference over all channels
    double maxAbs = 0;           // largest absolute difference of any channel
    double rmse = 0;
    double fractionWithin = 1;   // fraction of pixels whose channels all lie within tolerance
    long long pixelsOver = 0;    // pixels with some channel above tolerance
};

// Throws rt::Error when the sizes differ. clampToUnit = false compares raw floats (EXR checks).
ImageDiff compareImages(const Image& a, const Image& b, double tolerance, bool clampToUnit = true);

}  // namespace rt
