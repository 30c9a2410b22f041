// Progress and row windows: `rtlab render` draws its progress bar from
// Pipeline::setProgress, and the viewer renders a slow frame in pieces of rows
// (RenderOptions::rowBegin/rowEnd). The progress must only grow and end at its total, and the
// pieces of a frame must put together the frame rendered whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_scenes.h"

namespace rt {
namespace {

struct Case {
    std::string pipeline;
    PipelineVariant variant = {};  // the pipeline's defaults unless set
    int aa = 1;
    bool adaptive = false;
    double maxLaunchMs = 0;
    size_t memoryBudget = 0;  // bytes for a global ray tree (wave): row tiles smaller than pieces
};

std::string label(const Case& c) {
    return c.pipeline + (c.variant.name.empty() ? "" : " " + c.variant.name) + " aa" +
           std::to_string(c.aa) + (c.adaptive ? " adaptive" : "") +
           (c.maxLaunchMs > 0 ? " capped" : "") +
           (c.memoryBudget > 0 ? " budget " + std::to_string(c.memoryBudget) : "");
}

// Five rows of the tree wavefront's tree in the frames below: 64 pixels x (15 nodes x 48 B + one
// word of flags) a row on cornell (C = 2) at bounce limit 3.
constexpr size_t kRowBytes = 64 * (15 * 48 + 4);
constexpr size_t kFiveRows = 5 * kRowBytes;

// Every pipeline that renders row windows, in the settings that change its loops.
std::vector<Case> windowCases() {
    std::vector<Case> cases;
    for (const PipelineVariantRun& v : pipelineRegistry().variants())
        if (pipelineInfo(v.pipeline).supports.rowWindow) cases.push_back({v.pipeline, v.variant});
    for (const PipelineInfo& p : pipelineRegistry().all()) {
        if (!p.supports.rowWindow) continue;
        cases.push_back({p.name, {}, 2});
        if (p.supports.adaptiveAa) cases.push_back({p.name, {}, 2, true});
        if (p.supports.tiling)  // a tree of 5 rows of the frames below: several tiles a piece
            for (int aa : {1, 2}) cases.push_back({p.name, {}, aa, false, 0, kFiveRows});
    }
    return cases;
}

RenderOptions options(const Scene& scene, const Case& c) {
    RenderOptions o = scene.defaults;
    o.width = 64;
    o.height = 48;
    o.bounces = 3;
    o.pipelineOptions.setAll(c.variant.values);
    o.aa = c.aa;
    o.adaptiveAa = c.adaptive;
    o.maxLaunchMs = c.maxLaunchMs;
    o.memoryBudget = c.memoryBudget;
    return o;
}

double maxDifference(const Image& a, const Image& b, int rowBegin, int rowEnd) {
    double worst = 0;
    for (int y = rowBegin; y < rowEnd; ++y)
        for (int x = 0; x < a.width; ++x)
            for (int k = 0; k < 3; ++k)
                worst = std::max(worst, double(std::fabs(a.pixel(x, y)[k] - b.pixel(x, y)[k])));
    return worst;
}

TEST(RowWindows, ThePiecesOfAFrameMakeTheWholeFrame) {
    std::vector<Case> cases = windowCases();
    ASSERT_FALSE(cases.empty())
        << "no registered pipeline renders row windows (the viewer needs one)";
    Scene scene = test::load("cornell");  // glass: C = 2, and edges for the adaptive pass
    for (const Case& c : cases) {
        SCOPED_TRACE(label(c));
        std::unique_ptr<Pipeline> pipeline = makePipeline(c.pipeline, &test::device());
        RenderOptions o = options(scene, c);
        Image whole = pipeline->render(scene, o);
        Image assembled(o.width, o.height);
        // Uneven pieces, one of a single row, in order; then the last piece again alone, after
        // the others have left their rows in the pipeline's buffers.
        const std::vector<std::pair<int, int>> pieces = {{0, 7}, {7, 8}, {8, 31}, {31, 48}};
        for (auto [begin, end] : pieces) {
            o.rowBegin = begin;
            o.rowEnd = end;
            Image piece = pipeline->render(scene, o);
            for (int y = begin; y < end; ++y)
                std::copy_n(piece.pixel(0, y), size_t(o.width) * 3, assembled.pixel(0, y));
        }
        // The pipelines agree to 1e-5 (README); each with itself, piece by piece, exactly.
        EXPECT_EQ(maxDifference(whole, assembled, 0, o.height), 0.0);
    }
}

TEST(RowWindows, AWindowOutsideTheFrameIsRefusedByName) {
    Scene scene = test::load("spheres");
    std::unique_ptr<Pipeline> pipeline = makePipeline("mega", &test::device());
    RenderOptions o = options(scene, {"mega"});
    for (auto [begin, end] : std::vector<std::pair<int, int>>{{10, 10}, {-1, 5}, {40, 49}}) {
        o.rowBegin = begin;
        o.rowEnd = end;
        try {
            pipeline->render(scene, o);
            ADD_FAILURE() << "rows [" << begin << ", " << end << ") were rendered";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("row window"), std::string::npos) << e.what();
        }
    }
}

// What a pipeline reported through setProgress during one frame.
std::vector<std::pair<long long, long long>> progressOf(Pipeline& pipeline, const Scene& scene,
                                                        const RenderOptions& o) {
    std::vector<std::pair<long long, long long>> calls;
    pipeline.setProgress([&](long long done, long long total) { calls.emplace_back(done, total); });
    pipeline.render(scene, o);
    pipeline.setProgress({});
    return calls;
}

void expectMonotoneToTotal(const std::vector<std::pair<long long, long long>>& calls) {
    ASSERT_FALSE(calls.empty());
    const long long total = calls.front().second;
    EXPECT_GT(total, 0);
    long long last = 0;
    for (auto [done, t] : calls) {
        EXPECT_EQ(t, total) << "the total changed during the frame";
        EXPECT_GE(done, last) << "progress went back";
        EXPECT_LE(done, total);
        last = done;
    }
    EXPECT_EQ(calls.back().first, total) << "the frame ended short of its total";
}

TEST(Progress, GrowsAndEndsAtTheTotalInEveryPipelineThatReports) {
    Scene scene = test::load("cornell");
    std::vector<Case> cases = windowCases();
    // Launches capped far below a row's cost: one launch per row, each reported.
    cases.push_back({"mega", {}, 1, false, 1e-6});
    cases.push_back({"queue", {}, 2, false, 1e-6});
    cases.push_back({"wave", {}, 2, false, 1e-6});
    // The CPU reference reports rows as its threads finish them (it renders every row).
    cases.push_back({"cpu"});
    cases.push_back({"cpu", {}, 2, true});
    for (const Case& c : cases) {
        SCOPED_TRACE(label(c));
        std::unique_ptr<Pipeline> pipeline =
            makePipeline(c.pipeline, c.pipeline == "cpu" ? nullptr : &test::device());
        RenderOptions o = options(scene, c);
        auto calls = progressOf(*pipeline, scene, o);
        expectMonotoneToTotal(calls);
        if (c.pipeline == "mega") {
            // Rows x passes, one report per launch.
            EXPECT_EQ(calls.back().second, c.adaptive ? 2 * o.height : o.height);
            EXPECT_EQ(int(calls.size()), pipeline->stats().launches);
            if (c.maxLaunchMs > 0) EXPECT_GT(calls.size(), 8u) << "the cap split no launch";
        }
        if (c.pipeline == "queue")
            EXPECT_EQ(calls.back().second, (long long)(o.width) * o.height * o.aa * o.aa);
        if (c.pipeline == "wave") {
            // Rows x AA passes, one report per pass of a tile (trace, image and reset launches).
            EXPECT_EQ(calls.back().second, (long long)(o.height) * o.aa * o.aa);
            EXPECT_EQ(3 * int(calls.size()), pipeline->stats().launches);
            EXPECT_EQ(int(calls.size()), pipeline->stats().tiles * o.aa * o.aa);
            if (c.maxLaunchMs > 0) EXPECT_GT(pipeline->stats().tiles, 8) << "the cap split no tile";
            if (c.memoryBudget > 0) EXPECT_EQ(pipeline->stats().tiles, 10);  // 48 rows, 5 a tile
        }
        if (c.pipeline == "cpu") {
            EXPECT_EQ(calls.back().second, c.adaptive ? 2 * o.height : o.height);
            continue;  // no row windows
        }
        // A row window reports over its own rows.
        o.rowBegin = 10;
        o.rowEnd = 30;
        auto window = progressOf(*pipeline, scene, o);
        expectMonotoneToTotal(window);
        if (c.pipeline == "mega" && !c.adaptive) EXPECT_EQ(window.back().second, 20);
        if (c.pipeline == "wave") {
            EXPECT_EQ(window.back().second, 20 * o.aa * o.aa);
            if (c.memoryBudget > 0) EXPECT_EQ(pipeline->stats().tiles, 4);  // 20 rows, 5 a tile
        }
    }
}

// The tree wavefront's ray tree for a row window: a window smaller than a tile gets a tree of its
// own rows, not the whole frame's; a later window of the same frame keeps the larger tree instead
// of reallocating for every piece, but never more than the whole frame's tile. Its tiles are
// counted over the window's rows.
TEST(RowWindows, TheTreeWavefrontSizesItsTreeByTheWindow) {
    Scene scene = test::load("cornell");
    std::unique_ptr<Pipeline> wave = makePipeline("wave", &test::device());
    RenderOptions o = options(scene, {"wave"});
    auto treeBytes = [&] { return wave->stats().extras.value("tree_bytes", size_t(0)); };
    auto memoryTiles = [&] { return wave->stats().extras.value("memory_tiles", 0); };
    o.rowBegin = 7;
    o.rowEnd = 10;  // 3 rows, the whole frame fits one tile of 48
    wave->render(scene, o);
    EXPECT_EQ(treeBytes(), 3 * kRowBytes);
    EXPECT_EQ(memoryTiles(), 1);
    EXPECT_EQ(wave->stats().tiles, 1);
    o.rowBegin = 10;
    o.rowEnd = 11;  // a smaller piece keeps the tree of three rows
    wave->render(scene, o);
    EXPECT_EQ(treeBytes(), 3 * kRowBytes);
    o.rowBegin = 11;
    o.rowEnd = 48;  // a larger one grows it
    wave->render(scene, o);
    EXPECT_EQ(treeBytes(), 37 * kRowBytes);
    o.memoryBudget = kFiveRows;  // the budget caps what a window keeps: 5 rows, 8 tiles of 37
    wave->render(scene, o);
    EXPECT_EQ(treeBytes(), kFiveRows);
    EXPECT_EQ(memoryTiles(), 8);
    EXPECT_EQ(wave->stats().tiles, 8);
    o.rowBegin = o.rowEnd = 0;  // a whole frame sizes the tree to its tile exactly
    o.memoryBudget = 0;
    wave->render(scene, o);
    EXPECT_EQ(treeBytes(), 48 * kRowBytes);
    o.rowBegin = 0;
    o.rowEnd = 2;
    wave->render(scene, o);
    EXPECT_EQ(treeBytes(), 48 * kRowBytes);
    EXPECT_EQ(memoryTiles(), 1);
}

}  // namespace
}  // namespace rt
