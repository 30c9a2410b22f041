// `--pipeline auto`: the rule's branches, and that a frame is the chosen design's frame to the bit,
// chosen once per scene and settings, by prediction or by trial frames.
#include "auto/auto.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "megakernel/megakernel_options.h"
#include "persistent/persistent.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"

namespace rt {
namespace {

using test::sameBits;

// A wall of spheres two pixels across, half of them mirrors or glass at random, in front of a
// plane: the trees of neighbouring pixels disagree (the crossover map's left column, in small).
Scene divergentWall(int width, int height) {
    Scene s;
    s.name = "wall";
    auto material = [&](float reflectance, float opacity) {
        dev::Material m{};
        m.ambient = {0.05f, 0.05f, 0.05f}, m.diffuse = {0.7f, 0.3f, 0.2f};
        m.specular = {0.5f, 0.5f, 0.5f}, m.exponent = 50;
        m.reflectance = reflectance, m.opacity = opacity, m.ior = 1.5f;
        s.materials.push_back(m);
        s.materialNames.push_back("m" + std::to_string(s.materials.size()));
        return int(s.materials.size()) - 1;
    };
    const int plain = material(0, 1), mirror = material(0.9f, 1), glass = material(0, 0);
    s.camera.fovY = 40 * 3.14159265f / 180;  // from the origin along +z
    const float halfH = 10 * std::tan(s.camera.fovY / 2), pixel = 2 * halfH / float(height);
    const float halfW = halfH * float(width) / float(height);
    std::mt19937 rng(7);
    for (float y = -halfH + pixel; y < halfH; y += 2 * pixel)
        for (float x = -halfW + pixel; x < halfW; x += 2 * pixel) {
            const unsigned r = rng() % 4;
            const int m = r == 0 ? mirror : r == 1 ? glass : plain;
            s.spheres.push_back({{x, y, 10}, 0.95f * pixel, m, {0, 0, 0}});
        }
    s.planes.push_back({{0, 0, -1}, -12, plain, {0, 0, 0}});
    dev::Light light{};
    light.position = {2, 6, 0}, light.color = {1, 1, 1};
    s.lights = {light};
    finalizeScene(s);
    return s;
}

void setAuto(RenderOptions& o, const std::string& choice, const std::string& rule) {
    const PipelineInfo& info = pipelineInfo("auto");
    for (const PipelineOption& opt : info.options) {
        if (opt.name == "auto-choice") opt.set(o.pipelineOptions, choice);
        if (opt.name == "auto-rule") opt.set(o.pipelineOptions, rule);
    }
}

// The frame the named design renders, made with its own pipeline.
Image renderAs(const std::string& design, const Scene& scene, RenderOptions o) {
    std::string pipeline = design;
    if (design.rfind("mega-", 0) == 0) {
        pipeline = "mega";
        setMegaLayout(o, design == "mega-tree" ? MegaLayout::Tree : MegaLayout::Weighted);
    }
    if (design == "persist") setPersistentScheduleAuto(o);
    return makePipeline(pipeline, &test::device())->render(scene, o);
}

std::vector<std::string> names(const AutoKind& k) {
    std::vector<std::string> out;
    for (const AutoDesign& d : k.designs) out.push_back(d.name());
    return out;
}

TEST(AutoRule, EachBranchNamesItsDesignsAndWhy) {
    using V = std::vector<std::string>;
    LaneEstimate e;
    e.lanes = 32;
    AutoContext gpu;
    e.busyLanes = kQueueBelowLanes - kUncertainLanes;
    EXPECT_EQ(names(chooseKind(e, gpu)), (V{"queue", "persist"}));
    EXPECT_NE(chooseKind(e, gpu).reason.find("busy lanes of 32"), std::string::npos);
    e.busyLanes = kQueueBelowLanes + kUncertainLanes;
    EXPECT_EQ(names(chooseKind(e, gpu)), (V{"mega-weighted", "wave", "persist"}));
    // Near the threshold every design is timed, the predictor's side first.
    e.busyLanes = kQueueBelowLanes - 0.1;
    EXPECT_EQ(names(chooseKind(e, gpu)), (V{"queue", "mega-weighted", "wave", "persist"}));
    EXPECT_NE(chooseKind(e, gpu).reason.find("too close to call"), std::string::npos);
    e.busyLanes = kQueueBelowLanes;
    EXPECT_EQ(names(chooseKind(e, gpu)), (V{"mega-weighted", "wave", "persist", "queue"}));
    e.busyLanes = kQueueBelowLanes + kUncertainLanes;
    AutoContext tiled = gpu;
    tiled.waveFits = false;
    EXPECT_EQ(names(chooseKind(e, tiled)), (V{"mega-weighted", "persist"}));
    EXPECT_NE(chooseKind(e, tiled).reason.find("row tiles"), std::string::npos);
    AutoContext cpu = gpu;
    cpu.gpuRule = false;
    e.busyLanes = 3;  // lanes do not decide on a CPU
    EXPECT_EQ(names(chooseKind(e, cpu)), V{"mega-tree"});
    cpu.treeFits = false;
    EXPECT_EQ(names(chooseKind(e, cpu)), V{"mega-weighted"});
    AutoContext adaptive = gpu;
    adaptive.adaptive = true;
    EXPECT_EQ(names(chooseKind(e, adaptive)), V{"mega-tree"});
    EXPECT_NE(chooseKind(e, adaptive).reason.find("adaptive"), std::string::npos);
}

TEST(Auto, RendersTheDesignItNamesToTheBit) {
    const Scene wall = divergentWall(64, 32);
    const Scene empty = test::load("empty");
    struct Case {
        const Scene* scene;
        const char* choice;
        const char* rule;
        std::vector<std::string> designs;  // what it may pick
        size_t trials;                     // trial designs timed
    };
    // The wall's lanes are far below the GPU threshold, and the queue and the regrouped
    // persistent megakernel are timed; in the empty scene every pixel's tree is one ray, all 32
    // lanes busy, and the three one-tree designs are timed.
    for (const Case& c : {Case{&wall, "predict", "gpu", {"queue", "persist"}, 2},
                          Case{&wall, "lanes", "gpu", {"queue"}, 0},
                          Case{&empty, "predict", "gpu", {"mega-weighted", "wave", "persist"}, 3},
                          Case{&empty, "lanes", "gpu", {"mega-weighted"}, 0},
                          Case{&wall, "predict", "cpu", {"mega-tree"}, 0}}) {
        SCOPED_TRACE(std::string(c.scene->name) + " " + c.choice + ", rule " + c.rule);
        RenderOptions o = c.scene->defaults;
        o.width = 64, o.height = 32, o.bounces = 4;
        setAuto(o, c.choice, c.rule);
        AutoPipeline autoPipeline(test::device(), pipelineRegistry());
        const Image first = autoPipeline.render(*c.scene, o);
        const nlohmann::json x = autoPipeline.stats().extras;
        const std::string design = x.value("auto_design", "");
        EXPECT_NE(std::find(c.designs.begin(), c.designs.end(), design), c.designs.end())
            << x.dump();
        EXPECT_TRUE(x.value("auto_decided", false));
        EXPECT_EQ(x.contains("auto_trials_ms") ? x["auto_trials_ms"].size() : 0u, c.trials);
        const double lanes = x.value("auto_busy_lanes", -1.0);
        if (std::string(c.rule) == "gpu" && std::abs(lanes - kQueueBelowLanes) >= kUncertainLanes)
            EXPECT_EQ(x.value("auto_busy_lanes", -1.0) < kQueueBelowLanes,
                      design == "queue" || x.value("persist_schedule", "") == "regrouped");
        EXPECT_TRUE(sameBits(first, renderAs(design, *c.scene, o)));
        // The persistent megakernel chose its schedule from auto's estimate, not a second trace.
        if (design == "persist")
            EXPECT_EQ(x.value("persist_predict_ms", -1.0), x.value("auto_predict_ms", -2.0));
        // The next frame keeps the choice without predicting or timing again.
        const Image second = autoPipeline.render(*c.scene, o);
        const nlohmann::json& y = autoPipeline.stats().extras;
        EXPECT_FALSE(y.value("auto_decided", true));
        EXPECT_EQ(y.value("auto_design", ""), design);
        EXPECT_EQ(y.value("auto_busy_lanes", -1.0), x.value("auto_busy_lanes", -1.0));
        EXPECT_TRUE(sameBits(first, second));
    }
}

TEST(Auto, MeasureRendersTheFastestTrial) {
    const Scene scene = test::load("cornell");
    RenderOptions o = scene.defaults;
    o.width = 48, o.height = 32, o.bounces = 3;
    setAuto(o, "measure", "device");
    AutoPipeline autoPipeline(test::device(), pipelineRegistry());
    const Image image = autoPipeline.render(scene, o);
    const nlohmann::json& x = autoPipeline.stats().extras;
    const nlohmann::json& trials = x.at("auto_trials_ms");
    ASSERT_EQ(trials.size(), 5u) << trials.dump();  // both layouts, wave, queue and persist
    const std::string design = x.at("auto_design");
    for (const auto& [name, ms] : trials.items())
        EXPECT_LE(trials.at(design).get<double>(), ms.get<double>()) << name;
    EXPECT_TRUE(sameBits(image, renderAs(design, scene, o)));
    // A setting that changes the frame decides again.
    o.bounces = 2;
    autoPipeline.render(scene, o);
    EXPECT_TRUE(autoPipeline.stats().extras.value("auto_decided", false));
}

TEST(Auto, AdaptiveAntiAliasingGoesToTheMegakernel) {
    const Scene scene = divergentWall(32, 16);
    RenderOptions o = scene.defaults;
    o.width = 32, o.height = 16, o.aa = 2, o.adaptiveAa = true;
    setAuto(o, "predict", "gpu");
    AutoPipeline autoPipeline(test::device(), pipelineRegistry());
    const Image image = autoPipeline.render(scene, o);
    EXPECT_EQ(autoPipeline.stats().extras.value("auto_design", ""), "mega-tree");
    EXPECT_TRUE(sameBits(image, renderAs("mega-tree", scene, o)));
}

TEST(Auto, ABadChoiceIsOneClearError) {
    RenderOptions o;
    try {
        setAuto(o, "guess", "device");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--auto-choice guess: must be predict, lanes or measure");
    }
}

}  // namespace
}  // namespace rt
