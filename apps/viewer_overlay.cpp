// rtlab-view — overlay text. Mrays/s is device throughput: rays traced (counted on the device)
// over the frame's summed kernel time.
#include "apps/viewer_overlay.h"

#include <algorithm>
#include <cstdio>

#include "core/accel.h"

namespace rt::view {
namespace {

std::string format(const char* fmt, auto... args) {
    char buf[256];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}

double mib(size_t bytes) { return double(bytes) / (1024.0 * 1024.0); }

std::string pipelineLine(const PipelineFrame& p) {
    const FrameStats& s = p.stats;
    std::string line = format("%-4s %7.1f MS ", p.name.c_str(), s.deviceMs);
    for (const auto& [name, ms] : s.kernelMs) line += format(" %s %.1f", name.c_str(), ms);
    if (s.raysCounted && s.deviceMs > 0) {
        double rays = 0;
        for (uint64_t r : s.rays) rays += double(r);
        line += format("  %.2f MRAYS/S", rays / (s.deviceMs * 1e-3) / 1e6);
    }
    return line;
}

// A frame still coming in pieces: rows done, a bar, and the time so far.
std::string progressLine(const FrameOut& f) {
    constexpr int kWidth = 20;
    double done = f.height > 0 ? double(f.rowsDone) / f.height : 0;
    int filled = int(done * kWidth);
    return format("rendering rows %d/%d [%s%s] %.0f%%  piece %d  %.1f s", f.rowsDone, f.height,
                  std::string(size_t(filled), '#').c_str(),
                  std::string(size_t(kWidth - filled), '-').c_str(), 100 * done, f.pieces,
                  f.wallMs / 1000);
}

constexpr Rgba kBackground{0, 0, 0, 150}, kText{235, 235, 235, 255}, kDim{160, 200, 255, 255},
    kWarn{255, 190, 90, 255};

}  // namespace

const std::vector<std::string>& helpLines() {
    static const std::vector<std::string> lines = {
        "W/A/S/D  move            Q/E  down/up      shift  faster",
        "drag     turn (yaw/pitch); in split view, drag the divider",
        "M  next pipeline         V  split view     +/-  bounce limit",
        "B  accel none/bv/grid/bvh/wide (asks first: none, bv on a big mesh)",
        "R  reload scene    P  screenshot",
        "O  overlay   H  help   Esc  quit",
    };
    return lines;
}

TextCanvas makeOverlay(const OverlayInfo& info) {
    struct Line {
        std::string text;
        Rgba color;
    };
    std::vector<Line> lines;
    if (info.stats) {
        const FrameOut* f = info.frame;
        std::string mode = info.split ? "split " + info.pair[0] + "|" + info.pair[1] : info.pipeline;
        std::string head = f ? format("%s %dx%d", f->sceneName.c_str(), f->width, f->height) : "";
        lines.push_back({format("%s  %s  B %d  accel %s%s", head.c_str(), mode.c_str(), info.bounces,
                                accelName(info.accel), info.animate ? "  animated" : ""),
                         kText});
        if (f) {
            lines.push_back({format("FPS %.1f  frame %.0f ms  %s", info.fps, f->wallMs,
                                    info.framePath.c_str()),
                             kText});
            if (!f->complete()) lines.push_back({progressLine(*f), kWarn});
            // The largest buffer any pipeline on screen holds (the wavefront's ray tree).
            std::pair<std::string, size_t> largest;
            for (const PipelineFrame& p : f->pipelines) {
                lines.push_back({pipelineLine(p), kDim});
                for (const auto& b : p.stats.buffers)
                    if (b.second > largest.second) largest = b;
            }
            std::string mem = format("device memory %.1f MiB", mib(f->deviceBytes));
            if (largest.second)
                mem += format(" (%s %.1f MiB)", largest.first.c_str(), mib(largest.second));
            lines.push_back({mem, kText});
        } else {
            lines.push_back({"building kernels, first frame...", kText});
        }
    }
    for (const std::string& m : info.messages) lines.push_back({m, kWarn});
    if (info.help)
        for (const std::string& h : helpLines()) lines.push_back({h, kText});
    else if (info.stats)
        lines.push_back({"H help", kDim});

    size_t cols = 1;
    for (const Line& l : lines) cols = std::max(cols, l.text.size());
    TextCanvas canvas(int(std::min<size_t>(cols, 160)), int(std::max<size_t>(lines.size(), 1)),
                      kBackground);
    for (size_t i = 0; i < lines.size(); ++i) canvas.text(0, int(i), lines[i].text, lines[i].color);
    return canvas;
}

}  // namespace rt::view
