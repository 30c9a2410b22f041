// rtlab — image files through OpenImageIO (core/SHADING.md section 10). Float formats (EXR, HDR)
// keep linear 32-bit values; every other format is written clamped and sRGB-encoded in 8 bits
// and decoded back to linear on reading. The sRGB curve is applied here by hand, so the exact
// rounding is ours and not a colour-management setting of the OIIO build.
#include "image/image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/error.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const fs::path& path, const std::string& reason) {
    throw Error(path.string() + ": " + reason);
}

std::string lowerExtension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

bool isFloatFormat(const std::string& ext) { return ext == ".exr" || ext == ".hdr"; }

double srgbEncode(double c) {
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
}

double srgbDecode(double s) {
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

// The OIIO error of the last failed call, or a fallback.
std::string oiioError(const std::string& fallback) {
    std::string message = OIIO::geterror();
    while (!message.empty() && (message.back() == '\n' || message.back() == ' '))
        message.pop_back();
    return message.empty() ? fallback : message;
}

// Files that carry linear data despite an integer pixel format.
bool declaresLinear(const OIIO::ImageSpec& spec) {
    std::string space = spec.get_string_attribute("oiio:ColorSpace");
    std::transform(space.begin(), space.end(), space.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return space == "linear" || space == "scene_linear" || space == "lin_srgb";
}

}  // namespace

void writeImage(const Image& image, const fs::path& path) {
    const std::string ext = lowerExtension(path);
    if (ext.empty()) fail(path, "no file extension, cannot tell the image format");
    if (fs::is_directory(path)) fail(path, "is a directory");
    if (image.width <= 0 || image.height <= 0) fail(path, "cannot write an empty image");

    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path.string());
    if (!out) fail(path, "unknown image format '" + ext + "' (" + oiioError("no writer") + ")");

    const bool linear = isFloatFormat(ext);
    OIIO::ImageSpec spec(image.width, image.height, 3,
                         linear ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", linear ? "Linear" : "sRGB");
    if (!out->open(path.string(), spec))
        fail(path, "cannot write: " + oiioError("cannot open for writing"));

    bool ok;
    if (linear) {
        ok = out->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data());
    } else {
        std::vector<std::uint8_t> bytes(image.rgb.size());
        for (std::size_t i = 0; i < bytes.size(); ++i) {
            const float v = image.rgb[i];
            const double c = std::isnan(v) ? 0.0 : std::clamp(double(v), 0.0, 1.0);
            bytes[i] = std::uint8_t(std::lround(srgbEncode(c) * 255));
        }
        ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
    }
    const std::string writeError = ok ? "" : out->geterror();
    if (!out->close() && ok) fail(path, "cannot write: " + out->geterror());
    if (!ok) fail(path, "cannot write: " + writeError);
}

Image readImage(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) fail(path, "no such file");
    if (fs::is_directory(path, ec)) fail(path, "is a directory");

    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path.string());
    if (!in) fail(path, "cannot read image: " + oiioError("unknown or unreadable format"));
    const OIIO::ImageSpec spec = in->spec();
    const int channels = spec.nchannels;
    if (spec.width <= 0 || spec.height <= 0 || channels <= 0) fail(path, "image is empty");
    if (spec.depth > 1) fail(path, "volume images are not supported");

    // OIIO converts integer formats to [0, 1] floats.
    std::vector<float> data(std::size_t(spec.width) * spec.height * channels);
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, data.data()))
        fail(path, "cannot read pixels: " + in->geterror());
    in->close();

    const bool decode = !spec.format.is_floating_point() && !declaresLinear(spec);
    Image image(spec.width, spec.height);
    const std::size_t pixels = std::size_t(spec.width) * spec.height;
    for (std::size_t i = 0; i < pixels; ++i) {
        const float* src = &data[i * channels];
        for (int c = 0; c < 3; ++c) {
            // Gray (and gray + alpha) replicates channel 0; RGBA and more drop the rest.
            const float v = channels >= 3 ? src[c] : src[0];
            image.rgb[i * 3 + c] = decode ? float(srgbDecode(v)) : v;
        }
    }
    return image;
}

}  // namespace rt
