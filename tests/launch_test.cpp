// Time-bounded launches (issue 8): frames split into row tiles so that no launch runs past
// --max-launch-ms give the same image as one launch per frame.
#include <gtest/gtest.h>

#include <cstring>

#include "core/launch_planner.h"
#include "core/scene_loader.h"
#include "image/image_io.h"
#include "megakernel/megakernel.h"
#include "test_device.h"
#include "wavefront/tree/wavefront.h"

namespace rt {
namespace {

TEST(LaunchPlanner, LearnsRowsFromMeasuredTime) {
    LaunchPlanner p;
    p.begin(0, "a");
    EXPECT_EQ(p.nextRows(480), 480);  // disabled: the whole frame
    p.begin(100, "a");
    EXPECT_EQ(p.nextRows(480), 8);  // probe tile first
    p.record(8, 40.0);              // 5 ms per row -> 0.8 * 100 / 5 = 16 rows
    EXPECT_EQ(p.nextRows(480), 16);
    EXPECT_EQ(p.nextRows(10), 10);
    p.record(16, 1600.0);  // 100 ms per row: still at least one row
    EXPECT_EQ(p.nextRows(480), 1);
    p.begin(100, "b");  // another workload forgets
    EXPECT_EQ(p.nextRows(480), 8);
}

TEST(LaunchPlanner, TiledFramesEqualSingleLaunch) {
    Scene scene = loadScene("scenes/spheres.json", readImage);
    RenderOptions o = scene.defaults;
    o.width = 48;
    o.height = 40;
    o.bounces = 3;
    o.aa = 2;
    MegakernelPipeline mega(test::device());
    WavefrontPipeline wave(test::device());
    Image m1 = mega.render(scene, o), w1 = wave.render(scene, o);
    EXPECT_EQ(mega.stats().launches, 1);
    o.maxLaunchMs = 1e-3;  // far below any real launch: one row per launch after the probe
    Image m2 = mega.render(scene, o);
    Image w2 = wave.render(scene, o);
    EXPECT_GT(mega.stats().launches, 20);
    EXPECT_GT(wave.stats().tiles, 20);
    size_t bytes = m1.rgb.size() * sizeof(float);
    EXPECT_EQ(std::memcmp(m1.rgb.data(), m2.rgb.data(), bytes), 0);
    EXPECT_EQ(std::memcmp(w1.rgb.data(), w2.rgb.data(), bytes), 0);
    EXPECT_EQ(std::memcmp(m1.rgb.data(), w2.rgb.data(), bytes), 0);
}

}  // namespace
}  // namespace rt
