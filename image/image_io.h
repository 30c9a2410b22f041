// rtlab — image files through OpenImageIO. PNG (and other 8-bit formats) are written clamped and
// sRGB-encoded; EXR keeps linear 32-bit float. Failures throw rt::Error naming the file.
#pragma once

#include <filesystem>

#include "core/image.h"

namespace rt {

Image readImage(const std::filesystem::path& path);  // returns linear RGB
void writeImage(const Image& image, const std::filesystem::path& path);

}  // namespace rt
