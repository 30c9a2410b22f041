// rtlab — image comparison (core/SHADING.md section 10). OIIO's ImageBufAlgo::compare gives the
// mean, max and RMS error over all channels; a second pass over the same (clamped) pixels counts
// the pixels with any channel above the tolerance, the figure the accuracy gates use.
#include "image/compare.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"

namespace rt {
namespace {

std::string sizeOf(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

OIIO::ImageBuf toBuffer(const Image& image, bool clampToUnit) {
    OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT);
    OIIO::ImageBuf buffer(spec);
    buffer.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, image.rgb.data());
    if (!clampToUnit) return buffer;
    OIIO::ImageBuf clamped = OIIO::ImageBufAlgo::clamp(buffer, 0.f, 1.f);
    if (clamped.has_error()) throw Error("compareImages: clamp failed: " + clamped.geterror());
    return clamped;
}

}  // namespace

long long countNonFinite(const Image& image) {
    if (image.width <= 0 || image.height <= 0) return 0;
    const OIIO::ImageBuf raw = toBuffer(image, false);
    // Sum the channels: a pixel with a NaN or infinite channel has a non-finite sum (Inf - Inf is
    // NaN), so OIIO's NaN and Inf counts of the sum count such pixels once each.
    // One weight per channel: the default is a single weight, and OIIO then reads the other
    // channels' weights from past its end (seen as every pixel counted, now and then).
    const float weights[3] = {1.f, 1.f, 1.f};
    OIIO::ImageBuf sum = OIIO::ImageBufAlgo::channel_sum(raw, OIIO::cspan<float>(weights, 3));
    const OIIO::ImageBufAlgo::PixelStats stats = OIIO::ImageBufAlgo::computePixelStats(sum);
    if (sum.has_error() || stats.nancount.empty()) throw Error("countNonFinite: " + sum.geterror());
    return (long long)(stats.nancount[0] + stats.infcount[0]);
}

ImageDiff compareImages(const Image& a, const Image& b, double tolerance, bool clampToUnit) {
    if (a.width != b.width || a.height != b.height)
        throw Error("compareImages: size mismatch, " + sizeOf(a) + " vs " + sizeOf(b));
    ImageDiff diff;
    if (a.width <= 0 || a.height <= 0) return diff;
    const long long pixels = (long long)a.width * a.height;

    const OIIO::ImageBuf bufA = toBuffer(a, clampToUnit);
    const OIIO::ImageBuf bufB = toBuffer(b, clampToUnit);
    const OIIO::ImageBufAlgo::CompareResults result =
        OIIO::ImageBufAlgo::compare(bufA, bufB, float(tolerance), float(tolerance));
    // result.error is also set when pixels fail the threshold, so look at the buffers instead.
    if (bufA.has_error() || bufB.has_error())
        throw Error("compareImages: " + bufA.geterror() + bufB.geterror());
    diff.meanAbs = result.meanerror;
    diff.maxAbs = result.maxerror;
    diff.rmse = result.rms_error;

    // Per-pixel pass in double on the very floats OIIO compared.
    const float* pa = static_cast<const float*>(bufA.localpixels());
    const float* pb = static_cast<const float*>(bufB.localpixels());
    if (!pa || !pb) throw Error("compareImages: image buffers are not in memory");
    const float* ra = a.rgb.data();
    const float* rb = b.rgb.data();
    for (long long i = 0; i < pixels; ++i) {
        bool finite = true;
        for (int c = 0; c < 3; ++c)
            finite = finite && std::isfinite(ra[i * 3 + c]) && std::isfinite(rb[i * 3 + c]);
        if (!finite) {
            ++diff.nonfinite;
            ++diff.pixelsOver;
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(double(pa[i * 3 + c]) - double(pb[i * 3 + c]));
            if (!(d <= tolerance)) {  // NaN counts as over
                ++diff.pixelsOver;
                break;
            }
        }
    }
    diff.fractionWithin = double(pixels - diff.pixelsOver) / double(pixels);
    if (diff.nonfinite) {
        // OIIO compared clamped (or NaN-poisoned) values; no error figure of a frame with a
        // non-finite pixel is meaningful, so none may look small.
        diff.meanAbs = diff.maxAbs = diff.rmse = std::numeric_limits<double>::infinity();
    }
    return diff;
}

}  // namespace rt
