// Queue wavefront launch sizing (--queue-launch): launches sized on the device (every
// bounce enqueued at once, each kernel reading its real length from the counters) give the same
// bits as launches sized by a read-back per bounce, on every standard scene, at B 0..8 and with
// anti-aliasing; a pool too small for a bounce falls back to read-backs with the same bits; the
// frame reports its idle time and its read-backs; bad values are refused in one line; under
// --max-launch-ms a stage launch over more items than fit the cap goes in pieces.
#include <gtest/gtest.h>

#include <cstring>

#include "bench/sweep_config.h"
#include "core/error.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"
#include "wavefront/queue/queue.h"
#include "wavefront/queue/queue_split.h"

namespace rt {
namespace {

using test::kScenes;
using test::load;
using test::sameBits;
using Launch = QueueLaunchMode;

RenderOptions tiny(const Scene& scene, int bounces, int aa) {
    RenderOptions o = scene.defaults;
    o.width = 20;
    o.height = 14;
    o.bounces = bounces;
    o.aa = aa;
    return o;
}

class QueueLaunchSizing : public ::testing::TestWithParam<const char*> {};

// A path's result does not depend on when it runs, and each path's terms are added in the same
// order either way: the image must be the same bits.
TEST_P(QueueLaunchSizing, DeviceSizedLaunchesGiveTheSameBits) {
    Scene scene = load(GetParam());
    QueuePipeline queue(test::device());
    for (int b = 0; b <= 8; ++b)
        for (int aa : {1, 2}) {
            std::string what =
                std::string(GetParam()) + " B=" + std::to_string(b) + " aa=" + std::to_string(aa);
            RenderOptions o = tiny(scene, b, aa);
            setQueueLaunch(o, Launch::Readback);
            Image host = queue.render(scene, o);
            const int hostBounces = queue.queueStats().iterations;
            EXPECT_EQ(queue.queueStats().readbacks, hostBounces) << what << ": one per bounce";
            setQueueLaunch(o, Launch::Device);
            Image device = queue.render(scene, o);
            const QueueStats& q = queue.queueStats();
            EXPECT_FALSE(q.fellBack) << what << ": the default pool holds every bounce";
            EXPECT_EQ(q.readbacks, 0) << what;
            // One wave per AA sample here (the frame fits the pool): B + 1 bounces each.
            EXPECT_EQ(q.iterations, aa * aa * (b + 1)) << what;
            EXPECT_TRUE(sameBits(host, device)) << what;
        }
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, QueueLaunchSizing, ::testing::ValuesIn(kScenes));

// 64 slots: the waves are 64 camera rays, and glass and mirrors spawn more children than that
// at some bounce. Device sizing cannot cut paths, so it renders the frame again with read-backs.
TEST(QueueLaunch, PoolTooSmallForABounceFallsBackToReadbacks) {
    Scene scene = load("spheres");
    RenderOptions o = tiny(scene, 6, 1);
    setQueuePool(o, 64);
    QueuePipeline queue(test::device());
    Image host = queue.render(scene, o);
    ASSERT_GT(queue.queueStats().restartedPaths, 0)
        << "the pool must be too small to hold a bounce";
    setQueueLaunch(o, Launch::Device);
    Image device = queue.render(scene, o);
    EXPECT_TRUE(queue.queueStats().fellBack);
    EXPECT_EQ(queue.stats().extras.at("queue_launch"), "device, fell back to readback");
    EXPECT_TRUE(sameBits(host, device));
    // A pool that holds every bounce of the frame does not fall back.
    setQueuePool(o, 4096);
    EXPECT_TRUE(sameBits(host, queue.render(scene, o)));
    EXPECT_FALSE(queue.queueStats().fellBack);
}

// Several waves per AA sample (a pool smaller than the frame, large enough for each bounce).
TEST(QueueLaunch, DeviceSizingRunsTheFrameInWaves) {
    Scene scene = load("cornell");
    RenderOptions o = tiny(scene, 3, 1);
    o.width = 40;
    o.height = 30;  // 1200 pixels
    setQueuePool(o, 512);
    QueuePipeline queue(test::device());
    Image host = queue.render(scene, o);
    setQueueLaunch(o, Launch::Device);
    Image device = queue.render(scene, o);
    EXPECT_FALSE(queue.queueStats().fellBack);
    EXPECT_EQ(queue.queueStats().iterations, 3 * (3 + 1)) << "ceil(1200 / 512) waves of B + 1";
    EXPECT_TRUE(sameBits(host, device));
}

// The idle time is what device-side sizing could save at most: the span from the first kernel's
// start to the last one's end, less the time some kernel ran.
TEST(QueueLaunch, FrameReportsIdleTimeAndReadbacks) {
    Scene scene = load("cornell");
    QueuePipeline queue(test::device());
    for (Launch launch : {Launch::Readback, Launch::Device}) {
        RenderOptions o = tiny(scene, 4, 1);
        setQueueLaunch(o, launch);
        queue.render(scene, o);
        const FrameStats& s = queue.stats();
        std::string what = queueLaunchName(launch);
        ASSERT_TRUE(s.extras.contains("idle_ms")) << what;
        double idle = s.extras.at("idle_ms"), span = s.extras.at("span_ms");
        EXPECT_GE(idle, 0.0) << what;
        EXPECT_LE(idle, span) << what;
        EXPECT_GE(span, s.kernelMs.front().second) << what << ": the span holds every kernel";
        EXPECT_EQ(s.extras.at("queue_launch"), what);
        EXPECT_EQ(s.extras.at("readbacks"), queue.queueStats().readbacks);
        if (launch == Launch::Readback) EXPECT_GT(queue.queueStats().readbacks, 0);
    }
}

// StageCosts, on fake costs: a stage never measured gets a probe; then a piece is as many whole
// work-groups as fit 0.8 of the cap at the cost per item its last launches measured (pooled, so
// that launch overhead on a few items does not inflate it), and all of the queue when it fits.
TEST(QueueLaunch, StagePiecesFitTheCapFromTheMeasuredCostPerItem) {
    StageCosts costs;
    EXPECT_EQ(costs.piece("extend", 100000, 0, 64), 100000u) << "no cap: one launch";
    EXPECT_EQ(costs.piece("extend", 100000, 100, 64), StageCosts::kProbeItems) << "probe first";
    EXPECT_EQ(costs.piece("extend", 100, 100, 64), 100u) << "a short queue is its own probe";
    costs.learn("extend", 1024, 8.0, 100);                      // 1/128 ms an item: 10240 fit 80 ms
    EXPECT_EQ(costs.piece("extend", 100000, 100, 64), 10240u);  // 160 whole groups of 64
    EXPECT_EQ(costs.piece("extend", 100000, 100, 384), 9984u);  // 26 whole groups of 384
    EXPECT_EQ(costs.piece("extend", 10000, 100, 384), 10000u) << "fits: not cut to groups";
    EXPECT_EQ(costs.piece("shadow", 100000, 100, 64), StageCosts::kProbeItems) << "by stage";
    costs.learn("extend", 10, 1000.0, 100);  // 100 ms an item: still one work-group at least
    EXPECT_EQ(costs.piece("extend", 100000, 100, 64), 64u);
    costs.learn("extend", 0, 5.0, 100);  // an empty launch: nothing learned
    EXPECT_EQ(costs.piece("extend", 100000, 100, 64), 64u);
}

// A shared machine: the same stage takes twice as long from one bounce to the next. The pieces
// shrink by that spread, and a short launch (mostly launch overhead) does not move it.
TEST(QueueLaunch, StagePiecesShrinkWithTheSpreadOfLongLaunches) {
    StageCosts costs;
    costs.learn("extend", 1024, 16.0, 100);  // 1/64 ms an item
    EXPECT_EQ(costs.piece("extend", 100000, 100, 64), 5120u);
    EXPECT_DOUBLE_EQ(costs.slack(), 1.0);
    costs.learn("extend", 1024, 32.0, 100);  // twice as long: 1/32 ms an item, spread 2
    EXPECT_DOUBLE_EQ(costs.slack(), 2.0);
    EXPECT_EQ(costs.piece("extend", 100000, 100, 64), 1280u);  // 80 / (2 / 32)
    costs.learn("shadow", 64, 0.5, 100);
    costs.learn("shadow", 64, 5.0, 100);  // 10x, but 5 ms of a 100 ms cap: overhead, not told
    EXPECT_DOUBLE_EQ(costs.slack(), 2.0);
    costs.learn("shadow", 1024, 80.0, 100);  // as the last: the spread decays towards 1
    EXPECT_DOUBLE_EQ(costs.slack(), 1.9);
}

// --max-launch-ms bounds every launch, not only how many new paths a bounce admits: on the
// spheres (glass: a bounce can hold twice the rays of the last) the children of admitted paths
// and the resolve over every pixel are more items than fit the cap, and go in pieces over
// sub-ranges. A fake cost per item makes the pieces the same on any device; the image keeps the
// bits of one launch per stage.
TEST(QueueLaunch, StageLaunchesOverTheCapGoInPiecesWithTheSameBits) {
    Scene scene = load("spheres");
    RenderOptions o = tiny(scene, 6, 1);
    o.width = 64;
    o.height = 48;
    QueuePipeline queue(test::device());
    Image whole = queue.render(scene, o);
    const int wholeLaunches = queue.stats().launches;
    // 0.8 ms of the 1 ms cap fits 512 items (CPU groups of 64) or more, and the 256-item probes
    // stay under the cap; 3072 pixels and the glass children do not fit one launch.
    const size_t group = size_t(QueuePipeline::groupSize(test::device().device()));
    o.maxLaunchMs = 1.0;
    queue.setFakeItemMsForTest(1.0 / (2.5 * double(std::max<size_t>(group, 256))));
    for (int frame = 0; frame < 2; ++frame) {  // the second is sized from what the first learned
        Image split = queue.render(scene, o);
        EXPECT_TRUE(sameBits(whole, split)) << "frame " << frame;
        EXPECT_LE(queue.stats().longestLaunchMs, o.maxLaunchMs) << "frame " << frame;
        EXPECT_GT(queue.stats().launches, wholeLaunches) << "frame " << frame;
    }
}

TEST(QueueLaunch, DeviceSizingRefusesMaxLaunchMs) {
    Scene scene = load("cornell");
    RenderOptions o = tiny(scene, 2, 1);
    setQueueLaunch(o, Launch::Device);
    o.maxLaunchMs = 5;
    QueuePipeline queue(test::device());
    try {
        queue.render(scene, o);
        FAIL() << "--max-launch-ms learns from read-backs";
    } catch (const Error& e) {
        EXPECT_NE(
            std::string(e.what()).find("--queue-launch device does not go with --max-launch-ms"),
            std::string::npos)
            << e.what();
    }
}

TEST(QueueLaunch, NamesRoundTripAndABadNameIsOneLine) {
    for (Launch l : {Launch::Readback, Launch::Device})
        EXPECT_EQ(parseQueueLaunch(queueLaunchName(l)), l);
    try {
        parseQueueLaunch("persistent");
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--queue-launch persistent: must be readback or device");
    }
}

// bench/sweeps/queue-launch: both sizings of the queue on cornell 640x360 and spheres, B = 8.
TEST(QueueLaunch, SweepRunsBothSizings) {
    bench::SweepConfig c = bench::loadSweep(bench::findSweep("queue-launch"));
    std::map<std::string, Scene> scenes;
    std::vector<bench::Cell> cells =
        bench::expandCells(c, [&](const std::string& name) -> const Scene& {
            return scenes.try_emplace(name, load(name)).first->second;
        });
    int device = 0, readback = 0;
    for (const bench::Cell& cell : cells) {
        ASSERT_EQ(cell.pipeline, "queue");
        (queueLaunch(cell.options) == Launch::Device ? device : readback) += 1;
        EXPECT_EQ(cell.options.bounces, 8);
    }
    EXPECT_GT(device, 0);
    EXPECT_EQ(device, readback);
    // The PoCL file adds a pool that holds the frame, so device sizing runs one wave per sample.
    bench::SweepConfig cpu = bench::loadSweep(bench::findSweep("queue-launch-cpu"));
    int pooled = 0;
    for (const bench::Cell& cell :
         bench::expandCells(cpu, [&](const std::string& name) -> const Scene& {
             return scenes.try_emplace(name, load(name)).first->second;
         })) {
        EXPECT_EQ(cell.options.width, 640);
        if (queuePool(cell.options)) {
            EXPECT_GE(queuePool(cell.options), size_t(640 * 360));
            ++pooled;
        }
    }
    EXPECT_EQ(pooled, 4);
    bench::SweepConfig bad;
    try {
        bench::parseSweep("[g]\nscenes = cornell\nqueue-launch = sideways\n", "bad");
        FAIL() << "a bad queue-launch value must be refused";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("must be readback or device"), std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace rt
