// rtlab-view — what the overlay says: scene and settings, FPS, ms per kernel and Mrays/s for each
// pipeline on screen, device memory, recent messages, and the key help.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "apps/viewer_font.h"
#include "apps/viewer_renderer.h"

namespace rt::view {

struct OverlayInfo {
    const FrameOut* frame = nullptr;  // the frame on screen; null before the first one
    bool split = false;
    std::string pipeline;               // shown when not split
    std::array<std::string, 2> pair;    // split: left, right
    int bounces = 0;
    RenderOptions::Accel accel = RenderOptions::Accel::Bv;
    bool animate = false;
    double fps = 0;
    std::string framePath;              // "host copy", ...
    std::vector<std::string> messages;  // newest last
    bool stats = true, help = false;
};

TextCanvas makeOverlay(const OverlayInfo& info);

// The key help, also printed by --help.
const std::vector<std::string>& helpLines();

}  // namespace rt::view
