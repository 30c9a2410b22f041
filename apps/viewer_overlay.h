// rtlab-view — what the overlay says: scene and settings, FPS, ms per kernel and Mrays/s for each
// pipeline on screen, device memory, recent messages, and the key help; and how large it is
// drawn, from the framebuffer's size, so that it stays whole and leaves the image in view.
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
    std::string pipeline;             // shown when not split
    std::array<std::string, 2> pair;  // split: left, right
    int bounces = 0;
    RenderOptions::Accel accel = RenderOptions::Accel::Bv;
    bool animate = false;
    double fps = 0;
    std::string framePath;              // "host copy", ...
    std::vector<std::string> messages;  // newest last
    bool stats = true, help = false;
};

// The overlay panel's size on a framebuffer: whole window pixels per texel (scale) and the text
// cells it may hold. The stats take at most kStatsWidth of the width and kStatsHeight of the
// height; with the key help, which is asked for, up to kHelpWidth of the width and all of the
// height. The scale grows with the framebuffer while that leaves kReadableCols columns, up to
// kMaxScale (a 4K framebuffer then holds more columns, not larger letters). A
// window too narrow for kMinCols columns in its share (under about 500 pixels) gets them
// anyway, as far as its width goes: fewer would not say a pipeline's time on one row.
struct OverlayLayout {
    static constexpr double kStatsWidth = 0.25, kStatsHeight = 0.5, kHelpWidth = 0.75;
    static constexpr int kReadableCols = 24, kMinCols = 20, kMaxScale = 4;
    int scale = 1;
    int maxCols = 1, maxRows = 1;
};
OverlayLayout overlayLayout(int fbWidth, int fbHeight, bool help);

// The panel's text, wrapped into the layout's columns: a line too long continues on the next,
// indented. Should the rows still not fit, the per-kernel times go first, then the last rows
// (the last row left says "...").
struct OverlayRow {
    std::string text;
    Rgba color;
};
std::vector<OverlayRow> overlayRows(const OverlayInfo& info, const OverlayLayout& layout);
// Those rows drawn, at one texel per font pixel.
TextCanvas makeOverlay(const OverlayInfo& info, const OverlayLayout& layout);

// The key help, also printed by --help.
const std::vector<std::string>& helpLines();

}  // namespace rt::view
