// rtlab-view — linear float frames to the 8-bit sRGB bytes the window shows, with exactly the
// rounding image/image_io.cpp uses for PNG (so a screenshot equals `rtlab render -o x.png`), and
// back (screenshots are written through rt::writeImage, which encodes again).
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"

namespace rt::view {

// rgb gets width * height * 3 bytes, rows top first.
void encodeSrgb8(const Image& image, std::vector<uint8_t>& rgb);
// The inverse, chosen so that writeImage() turns each value back into the same byte.
Image decodeSrgb8(const std::vector<uint8_t>& rgb, int width, int height);

}  // namespace rt::view
