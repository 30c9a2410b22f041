// The sweep's time-left estimate (bench/sweep_eta.h), fed a made-up sequence of measured cells:
// what one kind of cell cost elsewhere prices it on the next scene or size, and a program's build
// is charged to the first cell of that program only.
#include "bench/sweep_eta.h"

#include <gtest/gtest.h>

#include <string>

namespace rt {
namespace {

using bench::Cell;
using bench::SweepEta;

Cell cell(const std::string& scene, const std::string& pipeline, int size = 64, int bounces = 2) {
    Cell c;
    c.scene = scene;
    c.pipeline = pipeline;
    c.options.width = c.options.height = size;
    c.options.bounces = bounces;
    c.options.aa = 1;
    c.options.shadowSamples = 1;
    return c;
}

TEST(SweepEta, QueueOnANewSceneCostsItsRatioToTheMegakernelMeasuredOnAnother) {
    SweepEta eta;
    eta.measured(cell("a", "mega"), 1.0, 0);
    eta.measured(cell("a", "queue"), 4.0, 0);
    eta.measured(cell("b", "mega"), 2.0, 0);
    // Scene b costs the megakernel twice scene a; the queue costs four times the megakernel.
    EXPECT_NEAR(eta.estimate(cell("b", "queue")), 8.0, 1e-6);
    EXPECT_NEAR(eta.estimate(cell("a", "queue")), 4.0, 1e-6);
    EXPECT_EQ(eta.cellsMeasured(), 3);
}

TEST(SweepEta, AnUnseenSizeScalesByTheRoughCostAndASeenOneByItsOwnFactor) {
    SweepEta eta;
    eta.measured(cell("a", "mega", 64), 1.0, 0);
    eta.measured(cell("a", "queue", 64), 3.0, 0);
    // Four times the pixels: four times the time, at the pipeline's own rate.
    EXPECT_NEAR(eta.estimate(cell("a", "mega", 128)), 4.0, 1e-6);
    EXPECT_NEAR(eta.estimate(cell("a", "queue", 128)), 12.0, 1e-6);
    // 128x128 measured slower than the pixels say (16 s, not 4): the queue there takes it too.
    eta.measured(cell("a", "mega", 128), 16.0, 0);
    EXPECT_NEAR(eta.estimate(cell("a", "queue", 128)), 48.0, 1e-6);
}

TEST(SweepEta, AProgramBuildIsChargedToTheFirstCellOfThatProgramOnly) {
    SweepEta eta;
    EXPECT_EQ(eta.estimate(cell("a", "mega")), 0) << "nothing measured: no estimate";
    eta.measured(cell("a", "mega", 64), 10.0, 8.0);  // 8 s building, 2 s of frames
    // The same program at four times the pixels: frames only.
    EXPECT_NEAR(eta.estimate(cell("a", "mega", 128)), 8.0, 1e-6);
    // Another bounce limit is another program: its frames (the rough cost's rays, 1 + B: 4 / 3
    // of B = 2's) plus the megakernel's build.
    const Cell b3 = cell("a", "mega", 64, 3), b3Large = cell("a", "mega", 128, 3);
    EXPECT_NEAR(eta.frameSeconds(b3), 2.0 * 4 / 3, 1e-6);
    EXPECT_NEAR(eta.buildSeconds(b3), 8.0, 1e-6);
    // Two pending cells of that program: one build between them.
    EXPECT_NEAR(eta.remaining({&b3, &b3Large}), 2.0 * 4 / 3 * 5 + 8.0, 1e-6);
    // Once its first cell started, the next is not charged again.
    eta.started(b3);
    EXPECT_NEAR(eta.estimate(b3Large), 2.0 * 4 / 3 * 4, 1e-6);
    // No build of the queue measured yet: the builds of any pipeline stand in.
    EXPECT_NEAR(eta.buildSeconds(cell("a", "queue")), 8.0, 1e-6);
}

TEST(SweepEta, AFailedCellCountsItsBuildButNotItsFrames) {
    SweepEta eta;
    eta.measured(cell("a", "mega"), 5.0, 3.0, /*ran=*/false);
    EXPECT_EQ(eta.cellsMeasured(), 0);
    EXPECT_EQ(eta.frameSeconds(cell("a", "mega", 128)), 0);
    EXPECT_NEAR(eta.buildSeconds(cell("a", "mega", 64, 5)), 3.0, 1e-6);
}

}  // namespace
}  // namespace rt
