// rtlab bench — Portable Float Map (.pfm) files: 32-bit linear RGB with no library behind them.
// rtlab-bench may not link OpenImageIO (it travels to the GPU machine alone), so it reads cubemap
// faces from, and writes frames for the accuracy comparison to, this format; `rtlab sweep` then
// compares those frames through OpenImageIO here.
#pragma once

#include <filesystem>

#include "core/image.h"

namespace rt::bench {

// Throws rt::Error naming the file.
void writePfm(const Image& image, const std::filesystem::path& path);
Image readPfm(const std::filesystem::path& path);

}  // namespace rt::bench
