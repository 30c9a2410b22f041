// Lights past 4 (issue 52: the SPD gears have 5, the tree 7): the ray-tree node's occlusion
// counts are sized per program (RT_NODE_LIGHTS), scenes of up to 4 lights keep the programs they
// had, every design renders 7 and 16 lights as the CPU reference does, and 17 are refused in one
// line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/pipeline.h"
#include "core/pipeline_registry.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "wavefront/bounce/bounce_state.h"

namespace rt {
namespace {

TEST(ManyLights, NodeKeepsTheLightsRoundedUpToFour) {
    EXPECT_EQ(dev::nodeLights(0), 4);
    EXPECT_EQ(dev::nodeLights(4), 4);
    EXPECT_EQ(dev::nodeLights(5), 8);
    EXPECT_EQ(dev::nodeLights(7), 8);
    EXPECT_EQ(dev::nodeLights(16), 16);
    EXPECT_EQ(sizeof(dev::Node), 48u) << "the host's records are the 4-light ones";
    EXPECT_EQ(dev::nodeBytes(7), 52u);
    EXPECT_EQ(dev::bounceHitBytes(16), sizeof(dev::BounceHit) + 12);
}

// A wall of spheres on a floor under `lights` coloured lights around the camera.
Scene manyLightScene(int lights) {
    Scene s;
    s.name = "lights" + std::to_string(lights);
    s.camera = {{0, 1.5f, -6}, 0, -0.2f, 0.9f, {0, 0}};
    dev::Material plain{};
    plain.diffuse = {0.7f, 0.7f, 0.7f};
    plain.specular = {0.3f, 0.3f, 0.3f};
    plain.exponent = 20;
    plain.opacity = plain.ior = 1;
    plain.patternScale = 1;
    dev::Material glass = plain;
    glass.opacity = 0.3f;
    glass.ior = 1.4f;
    s.materials = {plain, glass};
    s.materialNames = {"plain", "glass"};
    for (int i = 0; i < 5; ++i)
        s.spheres.push_back({{-2.f + i, 0.5f, float(i % 2)}, 0.45f, i % 2, {0, 0, 0}});
    s.planes.push_back({{0, 1, 0}, 0, 0, {0, 0, 0}});
    for (int j = 0; j < lights; ++j) {
        const float a = 6.2831853f * float(j) / float(lights);
        s.lights.push_back({{4 * std::cos(a), 3.f + 0.2f * float(j % 3), 4 * std::sin(a) - 2},
                            0.f,
                            {0.3f + 0.1f * float(j % 4), 0.25f, 0.4f - 0.05f * float(j % 5)},
                            0.f});
    }
    finalizeScene(s);
    return s;
}

TEST(ManyLights, ProgramsOfFourLightsOrFewerStayAsTheyWere) {
    auto has = [](const std::vector<std::string>& d, const std::string& s) {
        return std::find(d.begin(), d.end(), s) != d.end();
    };
    for (int n : {0, 1, 4}) {
        const Scene s = manyLightScene(n);
        for (const std::string& d : featureDefines(s, s.defaults))
            EXPECT_EQ(d.find("RT_NODE_LIGHTS"), std::string::npos) << n << " lights: " << d;
    }
    const Scene seven = manyLightScene(7);
    EXPECT_TRUE(has(featureDefines(seven, seven.defaults), "RT_NODE_LIGHTS=8"));
    const Scene sixteen = manyLightScene(16);
    EXPECT_TRUE(has(featureDefines(sixteen, sixteen.defaults), "RT_NODE_LIGHTS=16"));
}

// Every design and variant (both megakernel layouts, the tree and queue wavefronts, the
// persistent megakernel's schedules) with the accuracy bar of the megakernel's own test.
TEST(ManyLights, EveryDesignMatchesTheReference) {
    for (int n : {7, 16}) {
        const Scene scene = manyLightScene(n);
        RenderOptions base = scene.defaults;
        base.width = 48;
        base.height = 32;
        base.bounces = 3;
        base.accel = RenderOptions::Accel::Bvh;
        const Image cpu = renderReference(scene, base);
        for (const PipelineVariantRun& v : pipelineRegistry().variants(true)) {
            RenderOptions o = base;
            v.apply(o);
            auto pipeline = makePipeline(v.pipeline, &test::device());
            const Image img = pipeline->render(scene, o);
            const ImageDiff d = compareImages(img, cpu, 2.0 / 255.0);
            EXPECT_GE(d.fractionWithin, 0.999)
                << v.name << ", " << n << " lights: " << d.pixelsOver << " pixels over 2/255";
            EXPECT_LE(d.meanAbs, 0.5 / 255.0) << v.name << ", " << n << " lights";
        }
    }
}

TEST(ManyLights, SeventeenAreRefusedInOneLine) {
    Scene s = manyLightScene(16);
    s.lights.push_back(s.lights.back());
    s.source = "hand.json";
    try {
        finalizeScene(s);
        FAIL() << "17 lights accepted";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "hand.json: at most 16 lights, got 17");
    }
}

}  // namespace
}  // namespace rt
