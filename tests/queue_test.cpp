// Queue wavefront: the image of the megakernel's weighted layout on every standard
// scene (within 1e-5; bit-identical where each path is a single chain, C = 1), the same bits from
// run to run and for any pool size (paths cut for room and started again), device memory that
// does not grow with the bounce limit, the queues it claims to run, and one clear error per bad
// option.
#include "wavefront/queue/queue.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numeric>

#include "bench/sweep_config.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "megakernel/megakernel.h"
#include "megakernel/megakernel_options.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"
#include "wavefront/queue/queue_layout.h"

namespace rt {
namespace {

using test::kScenes;
using test::load;
using test::sameBits;

RenderOptions small(const Scene& scene, int bounces) {
    RenderOptions o = scene.defaults;
    o.width = 24;
    o.height = 18;
    o.bounces = bounces;
    return o;
}

// Queue and megakernel add a path's terms in a different order (bounce by bounce against depth
// first), so where paths branch (C = 2) the sums may differ in the last bit; with C = 1 the two
// orders are the same and so are the bits.
void expectSameImage(const Scene& scene, const RenderOptions& base, const std::string& what) {
    MegakernelPipeline mega(test::device());
    QueuePipeline queue(test::device());
    RenderOptions o = base;
    setMegaLayout(o, MegaLayout::Weighted);
    Image m = mega.render(scene, o), q = queue.render(scene, o);
    for (float v : q.rgb) ASSERT_TRUE(std::isfinite(v)) << what;
    ImageDiff d = compareImages(m, q, 1e-5, false);
    EXPECT_LE(d.maxAbs, 1e-5) << what;
    if (scene.branching() == 1) EXPECT_TRUE(sameBits(m, q)) << what << ": C = 1 must match bits";
}

class QueueVsMega : public ::testing::TestWithParam<const char*> {};

TEST_P(QueueVsMega, SameImageAsWeightedMegakernel) {
    Scene scene = load(GetParam());
    for (int b : {0, 1, 4, 12}) {
        RenderOptions o = small(scene, b);
        o.aa = b == 4 ? 2 : 1;
        o.shadowSamples = b == 1 ? 4 : 1;
        expectSameImage(scene, o, std::string(GetParam()) + " B=" + std::to_string(b));
    }
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, QueueVsMega, ::testing::ValuesIn(kScenes));

// The glass scene at bounce limits from 0 to 12 (the weighted megakernel is a program per limit
// when C = 2, so a sample): the widest trees, and the one that needs C = 2.
TEST(Queue, SameImageAtBounceLimitsFrom0To12WithGlass) {
    Scene scene = load("spheres");
    ASSERT_EQ(scene.branching(), 2);
    for (int b : {0, 1, 2, 3, 5, 8, 12}) {
        RenderOptions o = small(scene, b);
        o.width = 16;
        o.height = 12;
        expectSameImage(scene, o, "spheres B=" + std::to_string(b));
    }
}

// Compaction by prefix sum keeps every path's rays in a fixed order, whatever the pool size and
// however many paths were cut for room and started again.
TEST(Queue, SameBitsFromRunToRunAndForAnyPoolSize) {
    Scene scene = load("spheres");
    RenderOptions o = small(scene, 6);
    QueuePipeline queue(test::device());
    Image first = queue.render(scene, o);
    EXPECT_EQ(queue.queueStats().restartedPaths, 0);
    EXPECT_TRUE(sameBits(first, queue.render(scene, o)));
    setQueuePool(o, 64);  // C^B = 64: the least that holds one path's widest bounce
    Image tiny = queue.render(scene, o);
    EXPECT_GT(queue.queueStats().restartedPaths, 0) << "a 64-ray pool must cut paths";
    EXPECT_TRUE(sameBits(first, tiny));
    EXPECT_TRUE(sameBits(tiny, queue.render(scene, o)));
    setQueuePool(o, 1024);
    EXPECT_TRUE(sameBits(first, queue.render(scene, o)));
}

// --max-launch-ms only limits how many rays a bounce admits (learned from the launches it times,
// kept from frame to frame): the image stays the same bits, whatever the timings were.
TEST(Queue, LaunchTimeLimitChangesNoPixel) {
    Scene scene = load("cornell");
    RenderOptions o = small(scene, 5);
    o.width = 64;
    o.height = 48;
    QueuePipeline queue(test::device());
    Image free = queue.render(scene, o);
    o.maxLaunchMs = 1e-3;  // below any launch: admission drops to its floor
    Image first = queue.render(scene, o), second = queue.render(scene, o);
    EXPECT_TRUE(sameBits(free, first));
    EXPECT_TRUE(sameBits(free, second));
}

TEST(Queue, DeviceMemoryDoesNotGrowWithTheBounceLimit) {
    Scene scene = load("spheres");
    QueuePipeline queue(test::device());
    RenderOptions o = small(scene, 1);
    setQueuePool(o, 1 << 16);
    queue.render(scene, o);
    size_t shallow = queue.queueStats().poolBytes;
    EXPECT_EQ(shallow, queuePool(o) * QueuePipeline::bytesPerRay(2) + 4 + RT_Q_WORDS * 4);
    o.bounces = 16;
    queue.render(scene, o);
    EXPECT_EQ(queue.queueStats().poolBytes, shallow);
    EXPECT_EQ(queue.queueStats().queueLengths.size(), 17u);
    // The device-chosen pool is the same at every bounce limit too (C^16 = 65536 fits in it).
    EXPECT_EQ(QueuePipeline::poolSize(test::device().device(), 2, 0, RenderOptions{}),
              QueuePipeline::poolSize(test::device().device(), 2, 16, RenderOptions{}));
}

// Assert the architecture: the stages ran, one shade queue per class, every camera ray once.
TEST(Queue, RunsItsStagesOverClassQueues) {
    Scene scene = load("spheres");
    RenderOptions o = small(scene, 3);
    o.aa = 2;
    QueuePipeline queue(test::device());
    queue.render(scene, o);
    const FrameStats& s = queue.stats();
    std::vector<std::string> names;
    for (const auto& [name, ms] : s.kernelMs) names.push_back(name);
    for (const char* stage :
         {"generate", "extend", "shadow", "shade miss", "shade diffuse", "shade mirror",
          "shade glass", "scan blocks", "accumulate", "compact", "resolve"})
        EXPECT_NE(std::find(names.begin(), names.end(), stage), names.end()) << stage;
    const QueueStats& q = queue.queueStats();
    ASSERT_EQ(q.queueLengths.size(), 4u);
    const auto& primary = q.queueLengths[0];
    EXPECT_EQ(std::accumulate(primary.begin(), primary.end(), 0ll), 24ll * 18 * 4);
    EXPECT_GT(q.queueLengths[1][3], 0) << "spheres has glass seen through glass";
    EXPECT_EQ(s.extras.at("queue_lengths").size(), 4u) << "sweep rows carry them as extras";
    EXPECT_EQ(s.privateBytes, 0u);
}

TEST(Queue, RejectsAPoolThatCannotHoldOnePath) {
    Scene scene = load("spheres");  // C = 2
    RenderOptions o = small(scene, 12);
    setQueuePool(o, 1024);
    QueuePipeline queue(test::device());
    try {
        queue.render(scene, o);
        FAIL() << "4096 rays of one path do not fit 1024 slots";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("--pool 1024"), std::string::npos) << msg;
        EXPECT_NE(msg.find("use --pool 4096 or more"), std::string::npos) << msg;
    }
}

TEST(Queue, RejectsAdaptiveAntiAliasing) {
    Scene scene = load("spheres");
    RenderOptions o = small(scene, 2);
    o.aa = 2;
    o.adaptiveAa = true;
    QueuePipeline queue(test::device());
    try {
        queue.render(scene, o);
        FAIL() << "adaptive AA is the megakernel's";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--adaptive is not supported by the queue pipeline"),
                  std::string::npos)
            << e.what();
    }
}

// bench/sweeps/queue, the queue's benchmark: the headline against both megakernel layouts and the
// tree wavefront, and the queue along the bounce limit to 16.
TEST(Queue, BenchmarkSweepCoversTheHeadlineAndEveryBounceLimit) {
    bench::SweepConfig c = bench::loadSweep(bench::findSweep("queue"));
    Scene cornell = load("cornell");
    std::vector<bench::Cell> cells =
        bench::expandCells(c, [&](const std::string&) -> const Scene& { return cornell; });
    int queue = 0, weighted = 0, wave = 0;
    for (const bench::Cell& cell : cells) {
        queue += cell.pipeline == "queue";
        wave += cell.pipeline == "wave";
        weighted += cell.pipeline == "mega" && megaLayout(cell.options) == MegaLayout::Weighted;
        EXPECT_EQ(cell.options.width, 1920);
        EXPECT_EQ(cell.options.shadowSamples, 8);
    }
    EXPECT_EQ(queue, 17);  // B = 0..16, the headline's B = 8 among them
    EXPECT_EQ(weighted, 1);
    EXPECT_EQ(wave, 1);
}

}  // namespace
}  // namespace rt
