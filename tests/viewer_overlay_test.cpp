// The viewer's text overlay laid out for a framebuffer (apps/viewer_overlay.h), without a window:
// the split view's panel, with every kernel of a wavefront listed, stays inside the window and
// within its share of it at `rtlab view`'s default scale and at --scale 1, and still says
// everything where there is room for it.
#include "apps/viewer_overlay.h"

#include <gtest/gtest.h>

#include <string>

namespace rt::view {
namespace {

// A split frame of the megakernel and the queue wavefront, as the render thread hands it over.
FrameOut splitFrame() {
    FrameOut f;
    f.index = 7;
    f.width = 320;
    f.height = 240;
    f.rowsDone = 240;
    f.pieces = 1;
    f.wallMs = 181;
    f.sceneName = "cornell";
    f.deviceBytes = size_t(96) << 20;
    PipelineFrame mega{"mega", {}, {}};
    mega.stats.deviceMs = 41.5;
    mega.stats.kernelMs = {{"render", 41.5}};
    PipelineFrame queue{"queue", {}, {}};
    queue.stats.deviceMs = 97.3;
    queue.stats.kernelMs = {{"generate", 1.5},       {"trace", 40.25}, {"shade_diffuse", 20.5},
                            {"shade_specular", 9.0}, {"shadow", 18.0}, {"compact", 4.0},
                            {"accumulate", 4.0}};
    queue.stats.raysCounted = true;
    queue.stats.rays[0] = 5'000'000;
    queue.stats.buffers = {{"queues", size_t(48) << 20}};
    f.pipelines = {mega, queue};
    return f;
}

OverlayInfo splitInfo(const FrameOut& frame) {
    OverlayInfo info;
    info.frame = &frame;
    info.split = true;
    info.pair = {"mega", "queue"};
    info.bounces = 4;
    info.accel = RenderOptions::Accel::Bvh;
    info.fps = 5.5;
    info.framePath = "host copy";
    info.messages = {"bounce limit 4"};
    return info;
}

struct Window {
    int width, height;
    const char* what;
    double widthShare;  // the most of the width the stats may cover
};
// `rtlab view` renders 320x240 by default, in a window of twice that (the default scale), and
// at --scale 1 in one of that size; and the same on a high-DPI screen, and larger frames. At
// 320 pixels a quarter is 13 characters: the panel takes the 20 columns it needs (126 pixels).
constexpr Window kWindows[] = {{640, 480, "default scale", OverlayLayout::kStatsWidth},
                               {320, 240, "--scale 1", 0.4},
                               {1280, 960, "default scale, high-DPI", OverlayLayout::kStatsWidth},
                               {1280, 720, "--size 1280x720 --scale 1", OverlayLayout::kStatsWidth},
                               {3840, 2160, "4K", OverlayLayout::kStatsWidth}};

TEST(ViewerOverlay, SplitViewPanelIsInsideTheWindowAndWithinItsShareAtEveryScale) {
    const FrameOut frame = splitFrame();
    const OverlayInfo info = splitInfo(frame);
    for (const Window& w : kWindows) {
        SCOPED_TRACE(w.what);
        OverlayLayout layout = overlayLayout(w.width, w.height, false);
        TextCanvas canvas = makeOverlay(info, layout);
        const int width = canvas.width() * layout.scale, height = canvas.height() * layout.scale;
        EXPECT_GE(layout.scale, 1);
        // Drawn at the window's top left corner: inside it, and a small share of the image.
        EXPECT_LE(width, w.width * w.widthShare) << width << " of " << w.width;
        EXPECT_LE(height, w.height * OverlayLayout::kStatsHeight) << height << " of " << w.height;
        for (const OverlayRow& row : overlayRows(info, layout))
            EXPECT_LE(int(row.text.size()), layout.maxCols) << row.text;
    }
}

TEST(ViewerOverlay, SplitViewPanelKeepsEveryKernelTimeAtTheDefaultScale) {
    const FrameOut frame = splitFrame();
    const OverlayInfo info = splitInfo(frame);
    for (const Window& w : {kWindows[0], kWindows[2], kWindows[3]}) {
        SCOPED_TRACE(w.what);
        OverlayLayout layout = overlayLayout(w.width, w.height, false);
        // Columns enough for a phrase; the queue's line is longer and wraps.
        EXPECT_GE(layout.maxCols, 24);
        std::string text;
        for (const OverlayRow& row : overlayRows(info, layout)) {
            EXPECT_NE(row.text, "...");
            text += row.text + "\n";
        }
        for (const char* part : {"cornell 320x240", "split mega|queue", "FPS 5.5", "mega 41.5 MS",
                                 "queue 97.3 MS", "shade_specular 9.0", "accumulate 4.0",
                                 "device memory", "(queues 48.0 MiB)", "bounce limit 4", "H help"})
            EXPECT_NE(text.find(part), std::string::npos) << part << " missing from\n" << text;
    }
}

TEST(ViewerOverlay, NarrowPanelDropsKernelTimesBeforeItCutsRows) {
    const FrameOut frame = splitFrame();
    const OverlayInfo info = splitInfo(frame);
    OverlayLayout layout = overlayLayout(320, 240, false);
    std::string text;
    for (const OverlayRow& row : overlayRows(info, layout)) text += row.text + "\n";
    EXPECT_EQ(text.find("shade_specular"), std::string::npos) << text;
    EXPECT_NE(text.find("queue 97.3 MS"), std::string::npos) << text;
}

TEST(ViewerOverlay, KeyHelpFitsInsideTheWindow) {
    const FrameOut frame = splitFrame();
    OverlayInfo info = splitInfo(frame);
    info.help = true;
    for (const Window& w : kWindows) {
        SCOPED_TRACE(w.what);
        OverlayLayout layout = overlayLayout(w.width, w.height, true);
        TextCanvas canvas = makeOverlay(info, layout);
        EXPECT_LE(canvas.width() * layout.scale, w.width);
        EXPECT_LE(canvas.height() * layout.scale, w.height);
    }
    OverlayLayout layout = overlayLayout(640, 480, true);
    std::string text;
    for (const OverlayRow& row : overlayRows(info, layout)) text += row.text + "\n";
    EXPECT_NE(text.find("Esc  quit"), std::string::npos) << text;
}

}  // namespace
}  // namespace rt::view
