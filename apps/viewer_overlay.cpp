// rtlab-view — overlay text. Mrays/s is device throughput: rays traced (counted on the device)
// over the frame's summed kernel time.
#include "apps/viewer_overlay.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "core/accel.h"

namespace rt::view {
namespace {

std::string format(const char* fmt, auto... args) {
    char buf[256];
    std::snprintf(buf, sizeof buf, fmt, args...);
    return buf;
}

double mib(size_t bytes) { return double(bytes) / (1024.0 * 1024.0); }

// A line of the panel: parts that wrap as wholes (a kernel's name stays with its time); a
// detail part is left out when the panel is short of rows.
struct Part {
    std::string text;
    bool detail = false;
};
struct Line {
    std::vector<Part> parts;
    Rgba color;
};

// Free text (messages, the key help) as parts: its columns, at runs of three spaces or more.
std::vector<Part> columnsOf(const std::string& text) {
    std::vector<Part> parts;
    size_t at = 0;
    while (at < text.size()) {
        size_t gap = text.find("   ", at);
        std::string piece = text.substr(at, gap == std::string::npos ? gap : gap - at);
        if (!piece.empty()) parts.push_back({piece});
        if (gap == std::string::npos) break;
        at = text.find_first_not_of(' ', gap);
        if (at == std::string::npos) break;
    }
    return parts;
}

std::vector<Part> pipelineParts(const PipelineFrame& p) {
    const FrameStats& s = p.stats;
    std::vector<Part> parts = {{format("%s %.1f MS", p.name.c_str(), s.deviceMs)}};
    if (s.raysCounted && s.deviceMs > 0) {
        double rays = 0;
        for (uint64_t r : s.rays) rays += double(r);
        parts.push_back({format("%.2f MRAYS/S", rays / (s.deviceMs * 1e-3) / 1e6)});
    }
    for (const auto& [name, ms] : s.kernelMs)
        parts.push_back({format("%s %.1f", name.c_str(), ms), true});
    return parts;
}

// A frame still coming in pieces: rows done, a bar, and the time so far.
std::vector<Part> progressParts(const FrameOut& f) {
    constexpr int kWidth = 10;
    double done = f.height > 0 ? double(f.rowsDone) / f.height : 0;
    int filled = int(done * kWidth);
    return {{format("rendering rows %d/%d", f.rowsDone, f.height)},
            {format("[%s%s] %.0f%%", std::string(size_t(filled), '#').c_str(),
                    std::string(size_t(kWidth - filled), '-').c_str(), 100 * done)},
            {format("piece %d", f.pieces)},
            {format("%.1f s", f.wallMs / 1000)}};
}

// Rows of at most `cols` characters: parts joined by two spaces, a part that does not fit
// starting a new row, indented; a part wider than a row breaks at its spaces, and a word wider
// than a row anywhere.
std::vector<std::string> wrap(const std::vector<Part>& parts, int cols, bool details) {
    const size_t width = size_t(std::max(cols, 1));
    const std::string indent(width > 12 ? 2 : width > 4 ? 1 : 0, ' ');
    const size_t room = width - indent.size();  // what a piece may be, to fit a fresh row
    std::vector<std::string> rows = {""};
    bool started = false;  // the last row holds a piece
    auto place = [&](const std::string& piece, const char* gap) {
        if (!started) {
            rows.back() += piece;
            started = true;
        } else if (rows.back().size() + std::strlen(gap) + piece.size() <= width) {
            rows.back() += gap + piece;
        } else {
            rows.push_back(indent + piece);
        }
    };
    for (const Part& part : parts) {
        if ((part.detail && !details) || part.text.empty()) continue;
        if (part.text.size() <= room) {
            place(part.text, "  ");
            continue;
        }
        const char* gap = "  ";
        for (size_t at = 0; at < part.text.size(); gap = " ") {
            size_t end = std::min(part.text.find(' ', at), part.text.size());
            for (size_t cut = at; cut < end; cut += room) {
                place(part.text.substr(cut, std::min(room, end - cut)), gap);
                gap = " ";
            }
            at = end + 1;
        }
    }
    return rows;
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

OverlayLayout overlayLayout(int fbWidth, int fbHeight, bool help) {
    constexpr int kCell = TextCanvas::kCellWidth, kRow = TextCanvas::kCellHeight;
    constexpr int kEdges = 2 * TextCanvas::kMargin;
    OverlayLayout l;
    // The largest scale that leaves kReadableCols columns in the stats' share of the width.
    double statsWidth = std::max(fbWidth, 1) * OverlayLayout::kStatsWidth;
    l.scale = std::clamp(int(statsWidth / (OverlayLayout::kReadableCols * kCell + kEdges)), 1,
                         OverlayLayout::kMaxScale);
    double width =
        std::max(fbWidth, 1) * (help ? OverlayLayout::kHelpWidth : OverlayLayout::kStatsWidth);
    double height = std::max(fbHeight, 1) * (help ? 1.0 : OverlayLayout::kStatsHeight);
    auto columns = [&](double pixels) { return int((pixels / l.scale - kEdges) / kCell); };
    l.maxCols = std::max(1, std::min(std::max(columns(width), OverlayLayout::kMinCols),
                                     columns(std::max(fbWidth, 1))));
    l.maxRows = std::max(1, int((height / l.scale - kEdges) / kRow));
    return l;
}

std::vector<OverlayRow> overlayRows(const OverlayInfo& info, const OverlayLayout& layout) {
    std::vector<Line> lines;
    if (info.stats) {
        const FrameOut* f = info.frame;
        std::vector<Part> head;
        if (f) head.push_back({format("%s %dx%d", f->sceneName.c_str(), f->width, f->height)});
        head.push_back({info.split ? "split " + info.pair[0] + "|" + info.pair[1] : info.pipeline});
        head.push_back({format("B %d", info.bounces)});
        head.push_back({format("accel %s", accelName(info.accel))});
        if (info.animate) head.push_back({"animated"});
        lines.push_back({head, kText});
        if (f) {
            lines.push_back({{{format("FPS %.1f", info.fps)},
                              {format("frame %.0f ms", f->wallMs)},
                              {info.framePath, true}},
                             kText});
            if (!f->complete()) lines.push_back({progressParts(*f), kWarn});
            // The largest buffer any pipeline on screen holds (the wavefront's ray tree).
            std::pair<std::string, size_t> largest;
            for (const PipelineFrame& p : f->pipelines) {
                lines.push_back({pipelineParts(p), kDim});
                for (const auto& b : p.stats.buffers)
                    if (b.second > largest.second) largest = b;
            }
            std::vector<Part> mem = {{"device memory"}, {format("%.1f MiB", mib(f->deviceBytes))}};
            if (largest.second)
                mem.push_back(
                    {format("(%s %.1f MiB)", largest.first.c_str(), mib(largest.second)), true});
            lines.push_back({mem, kText});
        } else {
            lines.push_back({{{"building kernels, first frame..."}}, kText});
        }
    }
    for (const std::string& m : info.messages) lines.push_back({columnsOf(m), kWarn});
    if (info.help)
        for (const std::string& h : helpLines()) lines.push_back({columnsOf(h), kText});
    else if (info.stats)
        lines.push_back({{{"H help"}}, kDim});

    // Every detail while the rows fit, else none; rows past the last that fits become "...".
    std::vector<OverlayRow> rows;
    for (bool details : {true, false}) {
        rows.clear();
        for (const Line& l : lines)
            for (std::string& r : wrap(l.parts, layout.maxCols, details))
                rows.push_back({r, l.color});
        if (int(rows.size()) <= layout.maxRows) break;
    }
    if (int(rows.size()) > layout.maxRows) {
        rows.resize(size_t(std::max(layout.maxRows, 1)));
        rows.back() = {"...", kDim};
    }
    return rows;
}

TextCanvas makeOverlay(const OverlayInfo& info, const OverlayLayout& layout) {
    const std::vector<OverlayRow> rows = overlayRows(info, layout);
    size_t cols = 1;
    for (const OverlayRow& r : rows) cols = std::max(cols, r.text.size());
    TextCanvas canvas(int(cols), int(rows.size()), kBackground);
    for (size_t i = 0; i < rows.size(); ++i) canvas.text(0, int(i), rows[i].text, rows[i].color);
    return canvas;
}

}  // namespace rt::view
