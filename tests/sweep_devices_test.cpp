// Sweeps spread over devices and machines: two contexts on the one test device give
// the rows of a one-context run (same cells, same frames, in order), shards split the work units
// without overlap or gap and merge back into that order, a scene's stop-after-failure batches
// stay one unit, and bad --shard and --devices specs are refused by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "bench/sweep_runner.h"
#include "bench/sweep_schedule.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "test_device.h"
#include "test_sweep.h"

namespace rt {
namespace {

// A small sweep with interleaved batches, kept frames and a stop-after-failure group whose
// skips depend on an earlier failure (the private tree at B = 12).
const char* kSweep =
    "repeats = 1\nwarmup = 0\ncount-rays = yes\n"
    "[bounces]\nscenes = spheres cornell\npipelines = mega wave queue\nsizes = 24x16\nbounces = 1 "
    "2\n"
    "[accuracy]\nscenes = spheres\npipelines = mega wave\nsizes = 20x12\nbounces = 2\nimages = "
    "yes\n"
    "[limits]\nscenes = spheres\npipelines = mega wave\nsizes = 8x6 16x9\nbounces = 11..13\n"
    "stop-after-failure = yes\n";

struct SweepRun {
    std::vector<nlohmann::json> rows;
    std::vector<std::vector<float>> images;  // kept frames, in row order
    bench::SweepSummary summary;
};

SweepRun runSweep(const std::string& devices, bench::Shard shard = {}) {
    bench::SweepConfig config = bench::parseSweep(kSweep, "devices-test");
    bench::SweepRunOptions o;
    o.device = std::to_string(test::device().device().index);
    o.devices = devices;
    o.shard = shard;
    SweepRun r;
    r.summary =
        bench::runSweep(config, o, nullptr, [&](const nlohmann::json& row, const Image* image) {
            r.rows.push_back(row);
            if (image) r.images.push_back(image->rgb);
        });
    return r;
}

// A row without what differs from run to run (times, and what the launch planner learns from
// them); everything else must match.
nlohmann::json settled(nlohmann::json row) {
    for (const char* k : {"device_ms", "device_ms_min", "device_ms_max", "wall_ms", "frame_ms",
                          "kernel_ms", "longest_launch_ms", "launches", "mrays_per_s",
                          "accel_build_ms", "program_ms", "kernel_resources"})
        row.erase(k);
    // The queue pipeline's launch-sizing and shade-stage times (its read-back count stays).
    if (row.contains("extras"))
        for (const char* k : {"idle_ms", "span_ms", "shade_ms"}) row["extras"].erase(k);
    return row;
}

TEST(SweepDevices, TwoContextsOnOneDeviceGiveTheOneContextRows) {
    std::string index = std::to_string(test::device().device().index);
    SweepRun one = runSweep("");
    SweepRun two = runSweep(index + "," + index);
    // 12 + 2 + 12 cells; at B = 12 the megakernel's tree layout fails at 8x6 (rtlab's private-tree
    // cap, the same on every device), so its 16x9 B >= 12 and 8x6 B = 13 are recorded as skipped.
    // The tree wavefront keeps no private tree (its image kernel walks the global one) and runs
    // every cell.
    ASSERT_EQ(one.rows.size(), 26u);
    ASSERT_EQ(two.rows.size(), one.rows.size());
    EXPECT_EQ(two.summary.measured, one.summary.measured);
    EXPECT_EQ(two.summary.failed, 1);
    EXPECT_EQ(two.summary.notRun, 3);
    for (size_t i = 0; i < one.rows.size(); ++i) {
        EXPECT_EQ(one.rows[i]["cell_index"], i);  // cell order, as the sweep file lists them
        EXPECT_EQ(settled(two.rows[i]), settled(one.rows[i])) << "row " << i;
    }
    ASSERT_EQ(one.images.size(), 2u);
    EXPECT_EQ(two.images, one.images);  // the same frames, bit for bit
    ASSERT_TRUE(two.summary.meta.contains("devices"));
    EXPECT_EQ(two.summary.meta["devices"].size(), 2u);
    EXPECT_FALSE(one.summary.meta.contains("devices"));
}

TEST(SweepDevices, ShardsCoverEveryCellOnceAndMergeIntoCellOrder) {
    SweepRun whole = runSweep("");
    std::vector<nlohmann::json> merged;
    std::set<int> seen;
    for (int i = 0; i < 3; ++i) {
        SweepRun part = runSweep("", {i, 3});
        EXPECT_EQ(part.summary.meta["shard"], std::to_string(i) + "/3");
        EXPECT_EQ(part.summary.meta["sweep_cells"], 26);
        EXPECT_GT(part.rows.size(), 0u) << "shard " << i;
        for (const auto& row : part.rows) {
            EXPECT_TRUE(seen.insert(row["cell_index"].get<int>()).second) << row["cell"];
            merged.push_back(row);
        }
    }
    ASSERT_EQ(merged.size(), whole.rows.size());
    std::stable_sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) {
        return a["cell_index"].template get<int>() < b["cell_index"].template get<int>();
    });
    for (size_t i = 0; i < merged.size(); ++i)
        EXPECT_EQ(settled(merged[i]), settled(whole.rows[i])) << "row " << i;
}

TEST(SweepDevices, StopAfterFailureBatchesOfASceneAreOneUnit) {
    bench::SweepConfig config = bench::parseSweep(kSweep, "devices-test");
    Scene spheres = loadScene(std::string(RTLAB_SOURCE_DIR) + "/scenes/spheres.json");
    Scene cornell = loadScene(std::string(RTLAB_SOURCE_DIR) + "/scenes/cornell.json");
    std::vector<bench::Cell> cells = bench::expandCells(
        config,
        [&](const std::string& n) -> const Scene& { return n == "cornell" ? cornell : spheres; });
    std::vector<bench::WorkUnit> units = bench::workUnits(cells);
    // bounces: 2 scenes x 2 limits, one batch each (three pipelines interleaved); accuracy: one;
    // limits: 2 sizes x 3 bounce limits, one batch each, all one unit.
    ASSERT_EQ(units.size(), 6u);
    for (size_t u = 0; u < 5; ++u) {
        ASSERT_EQ(units[u].batches.size(), 1u) << u;
        EXPECT_FALSE(cells[units[u].batches[0].first].stopAfterFailure) << u;
    }
    EXPECT_EQ(units[5].batches.size(), 6u);
    size_t next = 0;  // every cell in exactly one unit, in order
    for (const auto& unit : units)
        for (auto [i, j] : unit.batches) {
            EXPECT_EQ(i, next);
            next = j;
        }
    EXPECT_EQ(next, cells.size());
}

TEST(SweepDevices, ShardSpecsAreParsedOrRefusedByName) {
    bench::Shard s = bench::parseShard("2/5");
    EXPECT_EQ(s.index, 2);
    EXPECT_EQ(s.count, 5);
    EXPECT_EQ(s.str(), "2/5");
    EXPECT_TRUE(bench::parseShard("0/1").whole());
    for (const char* bad : {"0/0", "3/2", "2/2", "x/y", "1", "-1/2", "1/2/3", "/2", "1/", ""}) {
        try {
            bench::parseShard(bad);
            ADD_FAILURE() << bad << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()).rfind("--shard " + std::string(bad) + ": ", 0), 0u)
                << e.what();
        }
    }
}

TEST(SweepDevices, DeviceListsAreResolvedOrRefusedByName) {
    const DeviceInfo& d = test::device().device();
    std::vector<DeviceInfo> two = bench::selectDevices(std::to_string(d.index) + "," + d.name);
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(two[0].index, d.index);
    EXPECT_EQ(two[1].index, d.index);
    // all: every GPU, else every device.
    std::vector<DeviceInfo> all = bench::selectDevices("all"), listed = listDevices();
    size_t gpus =
        std::count_if(listed.begin(), listed.end(), [](const DeviceInfo& x) { return x.isGpu(); });
    EXPECT_EQ(all.size(), gpus ? gpus : listed.size());
    for (auto [spec, named] : std::vector<std::pair<std::string, std::string>>{
             {"0,9999", "9999: no such device index"},
             {"nosuchdevice", "'nosuchdevice': no device name or platform matches"},
             {"0,,0", "an empty entry"}}) {
        try {
            bench::selectDevices(spec);
            ADD_FAILURE() << spec << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(std::string(e.what()).rfind("--devices " + spec + ": ", 0), 0u) << e.what();
            EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
        }
    }
}

// A row's timing extras come from its timed frames, not from the untimed ray-counting frame that
// follows them (its atomics slow it): the queue's span less its idle time is the last timed
// frame's kernel time, while the rays are counted.
TEST(SweepRows, TimingExtrasComeFromTheTimedFrames) {
    const std::vector<nlohmann::json> rows = test::sweepRows(
        "repeats = 3\nwarmup = 1\ncount-rays = yes\n[q]\nscenes = cornell\npipelines = queue\n"
        "sizes = 64x36\nbounces = 4\n",
        "extras-test");
    ASSERT_EQ(rows.size(), 1u);
    const nlohmann::json& r = rows[0];
    ASSERT_EQ(r["status"], "ok") << r.dump();
    EXPECT_EQ(r["rays"]["primary"].get<long long>(), 64 * 36);
    double busy = r["extras"]["span_ms"].get<double>() - r["extras"]["idle_ms"].get<double>();
    double last = r["frame_ms"].back().get<double>();
    EXPECT_NEAR(busy, last, 1e-6 * std::max(1.0, last)) << r["frame_ms"].dump();
}

// A sweep's cl-options reach every program it builds (an option the compiler refuses fails the
// cell, naming it) and every row, after whatever $RTLAB_CL_OPTIONS holds, and the environment is
// as it was once the sweep is done. The key belongs before the first group and takes something.
TEST(SweepRows, ClOptionsReachEveryBuildAndLeaveTheEnvironmentAsItWas) {
    const char* env = std::getenv("RTLAB_CL_OPTIONS");
    const std::string before = env ? env : "";
    const std::string cells =
        "repeats = 1\nwarmup = 0\ncount-rays = no\n[m]\nscenes = spheres\npipelines = mega\n"
        "sizes = 16x8\nbounces = 1\n";
    const std::vector<nlohmann::json> fine =
        test::sweepRows("cl-options = -DRT_SWEEP_OPTION_TEST=1\n" + cells, "cl-options-test");
    ASSERT_EQ(fine.size(), 1u);
    EXPECT_EQ(fine[0]["status"], "ok") << fine[0].dump();
    EXPECT_EQ(fine[0]["cl_options"],
              (before.empty() ? "" : before + " ") + "-DRT_SWEEP_OPTION_TEST=1");
    const std::vector<nlohmann::json> refused =
        test::sweepRows("cl-options = -cl-std=CL9.9\n" + cells, "cl-options-test");
    ASSERT_EQ(refused.size(), 1u);
    EXPECT_EQ(refused[0]["status"], "error") << refused[0].dump();
    EXPECT_NE(refused[0]["error"].get<std::string>().find("CL9.9"), std::string::npos)
        << refused[0].dump();
    const char* after = std::getenv("RTLAB_CL_OPTIONS");
    EXPECT_EQ(after ? std::string(after) : std::string(), before);
    EXPECT_EQ(after != nullptr, env != nullptr);
    for (const auto& [text, why] : std::vector<std::pair<std::string, std::string>>{
             {cells + "cl-options = -DX\n", "belongs before the first [group]"},
             {"cl-options =\n" + cells, "expected compiler options"}}) {
        try {
            bench::parseSweep(text, "cl-options-test");
            ADD_FAILURE() << text;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace rt
