// The limits sweep (bench/sweeps/limits): its file parses into what the charts expect,
// stop-after-failure skips exactly the settings no smaller than one that failed, rows say how
// each cell ended, and the two bugs it found stay fixed (a PoCL stack overflow in the wavefront
// image kernel at bounce limits 10 and 11, and NaN/1e14 pixels from unnormalized child rays).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "bench/sweep_config.h"
#include "bench/sweep_runner.h"
#include "core/error.h"
#include "core/launch_planner.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "megakernel/megakernel_options.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_sweep.h"
#include "wavefront/tree/wavefront.h"

namespace rt {
namespace {

using bench::Cell;
using bench::SweepConfig;

const Scene& spheres() {
    static Scene s = loadScene(std::string(RTLAB_SOURCE_DIR) + "/scenes/spheres.json");
    return s;
}

std::vector<Cell> cellsOf(const SweepConfig& c) {
    return bench::expandCells(c, [](const std::string&) -> const Scene& { return spheres(); });
}

TEST(LimitsSweep, FileParsesIntoLimitsGroups) {
    SweepConfig c = bench::loadSweep(bench::findSweep("limits"));
    ASSERT_EQ(c.groups.size(), 6u);
    for (const auto& g : c.groups) {
        EXPECT_EQ(g.name, "limits");
        EXPECT_TRUE(g.stopAfterFailure);
        EXPECT_DOUBLE_EQ(g.maxFrameS, 20);
        EXPECT_DOUBLE_EQ(g.maxLaunchMs, 100);
        EXPECT_EQ(g.scenes, std::vector<std::string>{"spheres"});
    }
    // Bounce limit 0..16 at 640x360: past both private-tree limits (B = 12).
    EXPECT_EQ(c.groups[0].bounces.front(), 0);
    EXPECT_EQ(c.groups[0].bounces.back(), 16);
    RenderOptions second;
    second.pipelineOptions = c.groups[1].pipelineOptions;
    EXPECT_EQ(megaLayout(second), MegaLayout::Weighted);
    EXPECT_EQ(c.groups[2].memoryBudget, size_t(32) << 20);
    EXPECT_EQ(c.groups[2].pipelines, std::vector<std::string>{"wave"});
    EXPECT_EQ(c.groups[3].bounces, std::vector<int>{8});
    EXPECT_EQ(c.groups[3].sizes.back(), std::make_pair(15360, 8640));
    // The queue wavefront on both axes (its memory is flat in B).
    EXPECT_EQ(c.groups[4].pipelines, std::vector<std::string>{"queue"});
    EXPECT_EQ(c.groups[4].bounces.back(), 16);
    EXPECT_EQ(c.groups[5].pipelines, std::vector<std::string>{"queue"});

    std::vector<Cell> cells = cellsOf(c);
    // The first and fourth groups run every device pipeline: the n - 1 besides the queue give
    // 17 + 6 cells each, less the 640x360 B=8 cell both axes share; the weighted megakernel and
    // the budgeted wavefront 17 each; the queue 17 + 6, less its shared cell.
    const size_t others = pipelineRegistry().names(true).size() - 1;
    EXPECT_EQ(cells.size(), 22 * others + 17 + 17 + 22);
    int shared = 0;
    for (const Cell& cell : cells) {
        EXPECT_TRUE(cell.stopAfterFailure);
        EXPECT_DOUBLE_EQ(cell.options.maxLaunchMs, 100);
        if (cell.groupIds == std::vector<int>{0, 3}) ++shared;
        EXPECT_EQ(cell.groups, std::vector<std::string>{"limits"});
    }
    EXPECT_EQ(size_t(shared), others);
    // A cell may be skipped after a smaller one fails: one size per measured batch. Cells of
    // one pipeline along the size axis (the fourth group) are each in a batch of their own.
    std::vector<std::string> sizeAxis;
    for (const Cell& cell : cells)
        if (cell.groupIds == std::vector<int>{3} && cell.pipeline == "mega")
            sizeAxis.push_back(cell.batchKey());
    ASSERT_GE(sizeAxis.size(), 2u);
    for (size_t i = 1; i < sizeAxis.size(); ++i) EXPECT_NE(sizeAxis[i - 1], sizeAxis[i]);
}

TEST(LimitsSweep, NewKeysAreValidated) {
    EXPECT_THROW(bench::parseSweep("stop-after-failure = maybe\n[limits]\nscenes = spheres\n", "x"),
                 Error);
    try {
        bench::parseSweep("[limits]\nscenes = spheres\nmax-frame-s = -1\n", "f");
        FAIL() << "a negative cap was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("f:3"), std::string::npos) << e.what();
    }
    SweepConfig c = bench::parseSweep("[quick]\nscenes = spheres\n", "q");
    EXPECT_FALSE(c.groups[0].stopAfterFailure);
    EXPECT_DOUBLE_EQ(c.groups[0].maxLaunchMs, 0);
    // Sweeps without the new keys keep their cell keys (--resume and old result sets): no launch
    // cap field, and the key recorded while every cell held the layout after its accel ("|0",
    // tree) reads as today's.
    Cell cell = cellsOf(c)[0];
    EXPECT_EQ(cell.key().find("|L"), std::string::npos);
    std::string recorded = cell.key();
    size_t accelEnd = 0;
    for (int field = 0; field < 7; ++field) accelEnd = recorded.find('|', accelEnd) + 1;
    recorded.insert(accelEnd, "0|");
    EXPECT_EQ(bench::currentCellKey(recorded), cell.key()) << recorded;
}

TEST(LimitsSweep, SkipsOnlySettingsNoSmallerThanAFailure) {
    SweepConfig c = bench::parseSweep(
        "stop-after-failure = yes\n"
        "[limits]\nscenes = spheres\nsizes = 64x36 128x72\nbounces = 3..5\n"
        "[other]\nscenes = spheres\nstop-after-failure = no\nsizes = 256x144\nbounces = 5\n",
        "tiny");
    std::vector<Cell> cells = cellsOf(c);
    auto find = [&](std::string k, int w, int b) {
        for (const Cell& x : cells)
            if (x.pipeline == k && x.options.width == w && x.options.bounces == b) return x;
        ADD_FAILURE() << "no cell " << w << " b" << b;
        return Cell{};
    };
    std::vector<bench::Stop> stops{{find("mega", 64, 4), "error: private tree"}};
    auto why = [&](std::string k, int w, int b) {
        return bench::skipReason(c, find(k, w, b), stops);
    };
    EXPECT_EQ(why("mega", 64, 4), "");  // the failed cell itself
    EXPECT_EQ(why("mega", 64, 3), "");  // smaller bounce limit
    EXPECT_EQ(why("wave", 64, 5), "");  // the other pipeline
    EXPECT_EQ(why("mega", 128, 5),
              "mega stopped at 64x36 B=4 (error: private tree); this setting is no smaller");
    EXPECT_NE(why("mega", 64, 5), "");
    EXPECT_NE(why("mega", 128, 4), "");
    EXPECT_EQ(why("mega", 128, 3), "");  // larger size but smaller bounce limit
    // Not in a group that stops after a failure.
    EXPECT_EQ(why("mega", 256, 5), "");
}

// Runs a sweep file's text on the test device; rows by "pipeline WxH bB".
std::map<std::string, nlohmann::json> run(const std::string& text,
                                          bench::SweepSummary* out = nullptr) {
    std::map<std::string, nlohmann::json> rows;
    for (const nlohmann::json& r : test::sweepRows(text, "limits-test", out)) {
        std::string key =
            r["pipeline"].get<std::string>() + " " + std::to_string(r["width"].get<int>()) + "x" +
            std::to_string(r["height"].get<int>()) + " b" + std::to_string(r["bounces"].get<int>());
        EXPECT_FALSE(rows.count(key)) << key;
        rows[key] = r;
    }
    return rows;
}

TEST(LimitsSweep, RowsRecordHowEachCellEnded) {
    bench::SweepSummary s;
    auto rows =
        run("repeats = 1\nwarmup = 0\ncount-rays = no\nmax-launch-ms = 100\n"
            "stop-after-failure = yes\n"
            "[limits]\nscenes = spheres\npipelines = mega wave\nsizes = 32x18\n"
            "bounces = 11..13\n"
            "[limits]\nscenes = spheres\npipelines = wave\nmemory-budget = 100K\n"
            "sizes = 32x18 64x36 320x180\nbounces = 3\n",
            &s);
    ASSERT_EQ(rows.size(), 9u);
    EXPECT_EQ(s.measured, 6);
    EXPECT_EQ(s.failed, 2);
    EXPECT_EQ(s.notRun, 1);
    for (const char* k : {"mega 32x18 b11", "wave 32x18 b11"}) {
        EXPECT_EQ(rows[k]["end"], "ran") << k;
        EXPECT_EQ(rows[k]["memory_tiles"], 1) << k;
        EXPECT_GE(rows[k]["launches"].get<int>(), 1) << k;
        EXPECT_GT(rows[k]["longest_launch_ms"].get<double>(), 0) << k;
        EXPECT_EQ(rows[k]["image_max_diff"], 0.0) << k;  // the pipelines agree bit for bit
        EXPECT_EQ(rows[k]["image_nonfinite"], 0) << k;
    }
    EXPECT_EQ(
        rows["mega 32x18 b12"]["end"],
        "error: --bounces 12: the megakernel's tree layout keeps 8191 ray-tree nodes (511 KiB) "
        "in private memory per work-item, over rtlab's 256 KiB cap; the highest bounce limit "
        "that fits is 11 (or use --layout weighted)");
    EXPECT_EQ(rows["mega 32x18 b12"]["failure"], "private_tree");
    EXPECT_EQ(rows["mega 32x18 b11"]["failure"], "");
    const char* k = "mega 32x18 b13";
    EXPECT_EQ(rows[k]["status"], "skipped");
    EXPECT_EQ(rows[k]["end"], "skipped");
    EXPECT_NE(rows[k]["skip_reason"].get<std::string>().find("stopped at 32x18 B=12"),
              std::string::npos);
    EXPECT_FALSE(rows[k].contains("device_ms"));
    EXPECT_EQ(rows[k]["failure"], "skipped");
    // The wavefront's image kernel walks the traced slots rather than copying the tree to private
    // memory, so only its global tree bounds it: it goes on past B = 12, in row tiles
    // where the device's largest allocation is smaller than the tree (B = 13: 453 MB).
    for (const char* w : {"wave 32x18 b12", "wave 32x18 b13"}) {
        EXPECT_EQ(rows[w]["end"].get<std::string>().rfind("ran", 0), 0u)
            << w << ": " << rows[w]["end"];
        EXPECT_EQ(rows[w]["status"], "ok") << w;
        EXPECT_EQ(rows[w]["image_nonfinite"], 0) << w;
        EXPECT_LT(rows[w]["private_bytes"].get<size_t>(), 1024u) << w;
    }
    // 32 pixels x (15 nodes x 48 B + 4 B of flags) = 23168 B a row; 100 KiB hold 4 of the 18
    // rows: 5 tiles.
    EXPECT_EQ(WavefrontPipeline::pixelBytes(2, 3), 724u);
    EXPECT_EQ(rows["wave 32x18 b3"]["end"], "ran (tiled into 5 tiles)");
    EXPECT_EQ(rows["wave 32x18 b3"]["tree_bytes"], 4 * 23168);
    EXPECT_EQ(rows["wave 64x36 b3"]["end"], "ran (tiled into 18 tiles)");  // 2 rows a tile
    // 320 x 724 = 231680 B: not even one row fits; 640x360 would not be tried.
    EXPECT_EQ(rows["wave 320x180 b3"]["failure"], "tree_row");
    EXPECT_NE(rows["wave 320x180 b3"]["end"].get<std::string>().find(
                  "error: one row of the wavefront ray tree at bounce limit 3"),
              std::string::npos);
}

TEST(LimitsSweep, FrameCapStopsLargerSettings) {
    bench::SweepSummary s;
    auto rows =
        run("repeats = 3\nwarmup = 0\ncount-rays = no\nstop-after-failure = yes\n"
            "max-frame-s = 0.000001\n"
            "[limits]\nscenes = spheres\npipelines = mega\nsizes = 32x18 64x36\nbounces = 1\n",
            &s);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows["mega 32x18 b1"]["end"], "ran");
    EXPECT_EQ(rows["mega 32x18 b1"]["frames"], 1);  // the cap ends the timed frames early too
    EXPECT_EQ(rows["mega 64x36 b1"]["end"], "skipped");
    EXPECT_NE(rows["mega 64x36 b1"]["skip_reason"].get<std::string>().find("over max-frame-s"),
              std::string::npos);
    EXPECT_EQ(s.notRun, 1);
}

TEST(LimitsSweep, EndStateAndFailureKind) {
    nlohmann::json ok = {{"status", "ok"},
                         {"pipeline", "wave"},
                         {"width", 10},
                         {"height", 7},
                         {"extras", {{"memory_tiles", 4}}}};
    EXPECT_EQ(bench::memoryTiles(ok), 4);
    EXPECT_EQ(bench::endState(ok), "ran (tiled into 4 tiles)");
    ok.erase("extras");  // a pipeline that never tiles reports no memory tiles
    EXPECT_EQ(bench::endState(ok), "ran");
    EXPECT_EQ(bench::endState({{"status", "error"}, {"error", "boom"}}), "error: boom");
    EXPECT_EQ(bench::endState({{"status", "skipped"}}), "skipped");
}

// The failure kind travels with the exception from where it is thrown; no code reads the message.
TEST(LimitsSweep, FailureKindsAreSetWhereThrown) {
    try {
        checkPrivateTree(2, 12, "test");
        FAIL() << "a 511 KiB private tree passed";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::PrivateTree);
    }
    try {
        WavefrontPipeline::tileRows(320, 180, 2, 3, 1024, "a budget");
        FAIL() << "a row over the budget passed";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::TreeRow);
    }
    EXPECT_EQ(std::string(failureKindName(FailureKind::OutOfMemory)), "out_of_memory");
    EXPECT_EQ(std::string(failureKindName(FailureKind::OpenCl)), "opencl");
    EXPECT_EQ(std::string(failureKindName(FailureKind::InvalidOption)), "invalid_option");
    EXPECT_EQ(std::string(failureKindName(FailureKind::Timeout)), "timeout");
    EXPECT_EQ(std::string(failureKindName(FailureKind::None)), "");
}

// Bounce limit 11 on spheres: every pixel finite and in range. Before the device normalized its
// child rays, rounding grew through refraction chains in the glass spheres (pixels of this frame
// far out of range, some NaN). The wavefront part also needs PoCL's worker threads to have room
// for 64 work-items' 256 KiB private trees (it crashed with SIGSEGV at bounce limits 10 and 11).
TEST(LimitsSweep, DeepBounceLimitsGiveSaneImages) {
    ClContext& cl = test::device();
    RenderOptions o = spheres().defaults;
    o.width = 160;
    o.height = 90;
    o.bounces = 11;
    o.memoryBudget = 64 << 20;
    Image images[2];
    int n = 0;
    for (std::string k : {"mega", "wave"}) {
        auto p = makePipeline(k, &cl);
        images[n] = p->render(spheres(), o);
        float worst = 0;
        for (float v : images[n].rgb) {
            ASSERT_TRUE(std::isfinite(v)) << k;
            worst = std::max(worst, v);
        }
        EXPECT_LT(worst, 2.0f) << k;
        ++n;
    }
    EXPECT_EQ(images[0].rgb, images[1].rgb);
}

// The watchdog point: rows differ in cost by 200x here (80 cheap rows of sky, then 20 rows of
// glass at 20 ms each). Planning from one average cost per row gave a 400 ms launch every frame
// (the limits sweep saw launches many times the target); with the per-row profile the first frame
// overshoots while it learns and from the third on every launch stays under the target.
TEST(LimitsSweep, LaunchPlannerLearnsCostlyRows) {
    auto cost = [](int row) { return row < 80 ? 0.1 : 20.0; };
    LaunchPlanner p;
    std::vector<double> longest;
    for (int frame = 0; frame < 4; ++frame) {
        p.begin(100, "spheres");
        double worst = 0;
        int launches = 0;
        for (int row = 0; row < 100;) {
            int rows = p.nextRows(100 - row);
            ASSERT_GE(rows, 1);
            double ms = 0;
            for (int r = row; r < row + rows; ++r) ms += cost(r);
            p.record(rows, ms);
            worst = std::max(worst, ms);
            row += rows;
            ++launches;
        }
        longest.push_back(worst);
        EXPECT_LT(launches, 60) << "frame " << frame;
    }
    EXPECT_GT(longest[0], 100);  // nothing known about the glass rows yet
    EXPECT_LE(longest[2], 100);
    EXPECT_LE(longest[3], 100);
    // A row that alone costs more than the target still gets a launch of its own.
    p.begin(100, "one costly row");
    EXPECT_EQ(p.nextRows(5), 1);  // the probe
    p.record(1, 300.0);
    EXPECT_EQ(p.nextRows(4), 1);
    p.record(1, 300.0);
    p.begin(100, "one costly row");
    EXPECT_EQ(p.nextRows(5), 1);
}

}  // namespace
}  // namespace rt
