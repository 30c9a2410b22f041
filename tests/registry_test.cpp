// The pipeline registry (issue 13): front ends see pipelines only through it, so it must list the
// CPU reference first and every pipeline folder once, refuse a second entry under one name, and
// name every choice when asked for one it lacks.
#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <string>

#include "bench/sweep_config.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "pipelines/registry.h"
#include "test_device.h"

namespace rt {
namespace {

TEST(Registry, ListsTheReferenceFirstAndEveryPipelineOnce) {
    const PipelineRegistry& r = pipelineRegistry();
    ASSERT_GE(r.all().size(), 3u);
    EXPECT_TRUE(r.all()[0].reference);
    std::set<std::string> seen;
    for (const PipelineInfo& p : r.all()) {
        EXPECT_TRUE(seen.insert(p.name).second) << p.name;
        EXPECT_FALSE(p.title.empty()) << p.name;
        EXPECT_FALSE(p.description.empty()) << p.name;
        EXPECT_EQ(p.reference, &p == &r.all()[0]) << "one reference, listed first: " << p.name;
    }
    // The two the project began with stay registered under their sweep-row names.
    EXPECT_NE(r.find("mega"), nullptr);
    EXPECT_NE(r.find("wave"), nullptr);
    EXPECT_EQ(r.names(true).size(), r.all().size() - 1);
}

TEST(Registry, EveryPipelineMakesOneThatKnowsItsName) {
    for (const PipelineInfo& p : pipelineRegistry().all()) {
        std::unique_ptr<Pipeline> made = makePipeline(p.name, &test::device());
        EXPECT_EQ(std::string(made->name()), p.name);
    }
}

TEST(Registry, UnknownNameListsEveryChoice) {
    try {
        pipelineInfo("gpu");
        FAIL() << "an unknown pipeline was found";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        std::string msg = e.what();
        EXPECT_NE(msg.find("--pipeline gpu"), std::string::npos) << msg;
        for (const std::string& n : pipelineRegistry().names())
            EXPECT_NE(msg.find(n), std::string::npos) << msg;
    }
}

TEST(Registry, RefusesADuplicateName) {
    PipelineRegistry r;
    r.add(referencePipelineInfo());
    EXPECT_THROW(r.add(referencePipelineInfo()), Error);
    EXPECT_THROW(r.make("mega", nullptr), Error);  // not in this registry
}

// What lets a new pipeline in without a test of its own: every device pipeline renders the same
// image as the first one registered (they share the stage code in core/cl): within 1e-5 per
// channel, the bar issue 14 set for a pipeline that adds a path's contributions in another order
// (the queue sums bounce by bounce, the megakernel depth first; float addition is not
// associative, so glass scenes differ in the last bit).
TEST(Registry, EveryDevicePipelineRendersTheSameImage) {
    Scene scene = loadScene("scenes/spheres.json", readImage);
    RenderOptions o = scene.defaults;
    o.width = 48;
    o.height = 32;
    o.bounces = 3;
    const std::vector<std::string> names = pipelineRegistry().names(true);
    Image first = makePipeline(names.at(0), &test::device())->render(scene, o);
    for (size_t i = 1; i < names.size(); ++i) {
        Image other = makePipeline(names[i], &test::device())->render(scene, o);
        ASSERT_EQ(other.rgb.size(), first.rgb.size()) << names[i];
        const ImageDiff d = compareImages(other, first, 1e-5, false);
        EXPECT_TRUE(d.allWithin()) << names[i] << " differs from " << names[0] << " by up to "
                                   << d.maxAbs << " (" << d.nonfinite << " non-finite pixels)";
    }
}

// Sweep files take any registered name, and every device pipeline when a group names none.
TEST(Registry, SweepFilesTakeTheirPipelinesFromTheRegistry) {
    bench::SweepConfig c = bench::parseSweep("[a]\nscenes = spheres\n[b]\nscenes = spheres\n"
                                             "pipelines = wave\n",
                                             "test");
    EXPECT_EQ(c.groups[0].pipelines, pipelineRegistry().names(true));
    EXPECT_EQ(c.groups[1].pipelines, std::vector<std::string>{"wave"});
    for (const char* bad : {"nope", "cpu"}) {
        try {
            bench::parseSweep(std::string("[a]\nscenes = spheres\npipelines = ") + bad + "\n", "f");
            FAIL() << bad << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), FailureKind::InvalidOption) << e.what();
            EXPECT_NE(std::string(e.what()).find("f:3: "), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
        }
    }
}

TEST(Registry, DevicePipelineNeedsADevice) {
    for (const std::string& n : pipelineRegistry().names(true))
        EXPECT_THROW(makePipeline(n, nullptr), Error) << n;
}

}  // namespace
}  // namespace rt
