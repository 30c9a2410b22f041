// The queue wavefront's packet stages (--queue-packets): on a CPU device with --accel
// wide, extend and shadow trace 16 queue entries per work-item (wavefront/queue/queue_packet.cl)
// and must give the image of the single-ray stages bit for bit: on the bunny (triangles and a
// ground plane), the knot (mirror-like gold, two lights), the Cornell box (spheres in the BVH's
// leaves, glass, an area light with several shadow samples), with launches sized on the device
// and with launches split under --max-launch-ms. A frame that loses one lane's hit must differ
// (the comparison sees every lane). Impossible choices are refused in one line; sweep files
// choose packets per group.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <set>

#include "bench/sweep_config.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"
#include "wavefront/queue/queue.h"

namespace rt {
namespace {

using Packets = QueuePacketMode;
using test::sameBits;

bool deviceIsCpu() { return test::device().device().type == "CPU"; }

RenderOptions small(const Scene& scene, int width, int height, int bounces) {
    RenderOptions o = scene.defaults;
    o.width = width;
    o.height = height;
    o.bounces = bounces;
    o.accel = RenderOptions::Accel::Wide;
    return o;
}

Scene bunny() { return loadScene(test::sharedFile("models/bunny.obj").string()); }

// Renders with packets off, then on, and expects the same bits and the packets reported; on a
// device that is not a CPU, `on` must be refused instead.
void expectSameBits(const Scene& scene, const RenderOptions& base, const std::string& what,
                    QueuePipeline& queue) {
    RenderOptions o = base;
    setQueuePackets(o, Packets::Off);
    Image single = queue.render(scene, o);
    EXPECT_EQ(queue.stats().extras.at("queue_packets"), 0) << what;
    setQueuePackets(o, Packets::On);
    if (!deviceIsCpu()) {
        EXPECT_THROW(queue.render(scene, o), Error) << what;
        return;
    }
    Image packets = queue.render(scene, o);
    EXPECT_EQ(queue.stats().extras.at("queue_packets"), QueuePipeline::kPacket) << what;
    EXPECT_TRUE(sameBits(single, packets)) << what;
}

TEST(QueuePackets, BunnyGivesTheSameBitsWithAndWithoutPackets) {
    const auto path = test::sharedFile("models/bunny.obj");
    RTLAB_REQUIRE_FILE(path);
    Scene scene = bunny();
    QueuePipeline queue(test::device());
    // 77 x 41: 3157 camera rays, so the last packet of the first bounce is partial.
    expectSameBits(scene, small(scene, 77, 41, 2), "bunny B=2", queue);
    RenderOptions o = small(scene, 48, 32, 2);
    o.aa = 2;
    expectSameBits(scene, o, "bunny aa=2", queue);
}

TEST(QueuePackets, StandardScenesGiveTheSameBitsWithAndWithoutPackets) {
    QueuePipeline queue(test::device());
    for (const char* name : {"mesh", "cornell"}) {
        Scene scene = test::load(name);
        expectSameBits(scene, small(scene, 40, 30, 4), std::string(name) + " B=4", queue);
    }
    // Several samples of the area light: a shadow packet per sample.
    Scene cornell = test::load("cornell");
    RenderOptions o = small(cornell, 40, 30, 3);
    o.shadowSamples = 4;
    expectSameBits(cornell, o, "cornell 4 shadow samples", queue);
    setQueueLaunch(o, QueueLaunchMode::Device);
    o.maxLaunchMs = 0;
    expectSameBits(cornell, o, "cornell, launches sized on the device", queue);
}

// The test above must be able to fail: a frame whose packets lose the hit of lane 5 (every
// 16th ray) differs from the single-ray frame.
TEST(QueuePackets, ALaneWhoseHitIsDroppedChangesTheImage) {
    if (!deviceIsCpu()) GTEST_SKIP() << "packets run on CPU devices only";
    const auto path = test::sharedFile("models/bunny.obj");
    RTLAB_REQUIRE_FILE(path);
    Scene scene = bunny();
    RenderOptions o = small(scene, 77, 41, 2);
    QueuePipeline queue(test::device());
    setQueuePackets(o, Packets::Off);
    Image single = queue.render(scene, o);
    setQueuePackets(o, Packets::On);
    EXPECT_TRUE(sameBits(single, queue.render(scene, o)));
    queue.setDropLaneForTest(5);
    Image dropped = queue.render(scene, o);
    size_t differ = 0;
    for (size_t i = 0; i < single.rgb.size(); ++i) differ += single.rgb[i] != dropped.rgb[i];
    EXPECT_GT(differ, 0u);
}

// --max-launch-ms splits extend and shadow into pieces of whole groups of packets (each piece
// starts at a multiple of 16 entries): more launches, the same bits.
TEST(QueuePackets, SplitLaunchesKeepTheBits) {
    if (!deviceIsCpu()) GTEST_SKIP() << "packets run on CPU devices only";
    Scene scene = test::load("mesh");
    RenderOptions o = small(scene, 96, 64, 2);
    setQueuePackets(o, Packets::On);
    QueuePipeline queue(test::device());
    Image whole = queue.render(scene, o);
    const int wholeLaunches = queue.stats().launches;
    const size_t group = size_t(QueuePipeline::groupSize(test::device().device()));
    const size_t step = group * size_t(QueuePipeline::kPacket);
    // 0.8 ms of the 1 ms cap fits two steps of packet items; 6144 pixels do not fit one launch.
    o.maxLaunchMs = 1.0;
    queue.setFakeItemMsForTest(1.0 / (2.5 * double(step)));
    for (int frame = 0; frame < 2; ++frame) {
        Image split = queue.render(scene, o);
        EXPECT_TRUE(sameBits(whole, split)) << "frame " << frame;
        EXPECT_LE(queue.stats().longestLaunchMs, o.maxLaunchMs) << "frame " << frame;
        EXPECT_GT(queue.stats().launches, wholeLaunches) << "frame " << frame;
    }
}

TEST(QueuePackets, AutoUsesPacketsOnCpuDevicesForTriangleScenesOnly) {
    Scene mesh = test::load("mesh"), cornell = test::load("cornell");
    const DeviceInfo& dev = test::device().device();
    RenderOptions o = small(mesh, 8, 8, 1);
    EXPECT_EQ(QueuePipeline::usesPackets(dev, mesh, o), dev.type == "CPU");
    EXPECT_FALSE(QueuePipeline::usesPackets(dev, cornell, o)) << "spheres: single rays";
    setQueuePackets(o, Packets::Off);
    EXPECT_FALSE(QueuePipeline::usesPackets(dev, mesh, o));
    setQueuePackets(o, Packets::Auto);
    o.accel = RenderOptions::Accel::Bvh;
    EXPECT_FALSE(QueuePipeline::usesPackets(dev, mesh, o));
}

void expectRefused(const Scene& scene, const RenderOptions& o, const DeviceInfo& dev,
                   const std::string& message) {
    try {
        QueuePipeline::usesPackets(dev, scene, o);
        ADD_FAILURE() << "expected: " << message;
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), message);
    }
}

TEST(QueuePackets, ImpossibleChoicesAreRefusedInOneLine) {
    Scene mesh = test::load("mesh"), spheres = test::load("spheres");
    DeviceInfo cpu;
    cpu.type = "CPU";
    cpu.name = "some CPU";
    RenderOptions o = small(mesh, 8, 8, 1);
    setQueuePackets(o, Packets::On);
    o.accel = RenderOptions::Accel::Bvh;
    expectRefused(mesh, o, cpu,
                  "--queue-packets on: packets traverse the wide BVH only (use --accel wide)");
    o.accel = RenderOptions::Accel::Wide;
    expectRefused(spheres, o, cpu,
                  "--queue-packets on: packets trace triangles, and the scene has none");
    DeviceInfo gpu = cpu;
    gpu.type = "GPU";
    gpu.name = "NVIDIA H200";
    expectRefused(mesh, o, gpu,
                  "--queue-packets on: packets are for CPU devices, and NVIDIA H200 is a GPU");
    EXPECT_TRUE(QueuePipeline::usesPackets(cpu, mesh, o));
}

TEST(QueuePackets, NamesRoundTripAndABadNameIsOneLine) {
    for (Packets p : {Packets::Auto, Packets::On, Packets::Off})
        EXPECT_EQ(parseQueuePackets(queuePacketsName(p)), p);
    try {
        parseQueuePackets("sometimes");
        FAIL() << "a bad value must be refused";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--queue-packets sometimes: must be auto, on or off");
    }
}

// Sweep files choose too: `queue-packets = on off` gives one cell of each, apart in their keys
// and labels; a bad value is refused naming it.
TEST(QueuePackets, SweepGroupsChooseThem) {
    bench::SweepConfig c = bench::parseSweep(
        "[g]\nscenes = mesh\npipelines = queue\nsizes = 32x24\naccel = wide\n"
        "queue-packets = off\n[h]\nscenes = mesh\npipelines = queue\nsizes = 32x24\n"
        "accel = wide\nqueue-packets = on\n",
        "packets");
    std::map<std::string, Scene> scenes;
    std::vector<bench::Cell> cells =
        bench::expandCells(c, [&](const std::string& name) -> const Scene& {
            return scenes.try_emplace(name, test::load(name)).first->second;
        });
    ASSERT_EQ(cells.size(), 2u);
    std::set<Packets> seen;
    for (const bench::Cell& cell : cells) {
        seen.insert(queuePackets(cell.options));
        EXPECT_NE(cell.label().find(std::string("packets ") +
                                    queuePacketsName(queuePackets(cell.options))),
                  std::string::npos)
            << cell.label();
    }
    EXPECT_EQ(seen, (std::set<Packets>{Packets::On, Packets::Off}));
    EXPECT_NE(cells[0].settingKey(), cells[1].settingKey());
    try {
        bench::parseSweep("[g]\nscenes = mesh\nqueue-packets = sometimes\n", "bad");
        FAIL() << "a bad queue-packets value must be refused";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("--queue-packets sometimes: must be auto, on or off"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace rt
