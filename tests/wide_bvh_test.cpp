// The 4-wide BVH of --accel wide (issue 18): the collapsed tree's invariants on the host
// (checkWide: every primitive in one leaf, every decoded box on its path holding it, the device
// stack never overflowing), and images that match --accel none with both pipelines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "core/accel.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_scenes.h"

namespace rt {
namespace {

namespace fs = std::filesystem;
using Accel = RenderOptions::Accel;

using test::kScenes;
using test::load;


void expectValidWide(const Scene& scene, const std::string& name) {
    AccelData d = buildAccel(scene, Accel::Wide);
    EXPECT_EQ(checkWide(d), "") << name;
    EXPECT_EQ(checkBvh(d), "") << name;  // the binary tree it came from
    EXPECT_EQ(d.stats.nodes, (long long)d.wide.size()) << name;
    EXPECT_EQ(d.stats.name, "wide");
    if (d.bvh.size() > 1) EXPECT_LT(d.wide.size(), d.bvh.size() / 2) << name;
}

TEST(WideBvh, EveryPrimitiveInOneLeafInsideEveryDecodedBoxOnItsPath) {
    for (const char* name : kScenes) expectValidWide(load(name), name);
    expectValidWide(test::soup(3000, 5000, 1), "soup");
    expectValidWide(test::soup(1, 0, 2), "one sphere");
    expectValidWide(test::soup(0, 1, 3), "one triangle");
    Scene same = test::soup(0, 0, 4);
    for (int i = 0; i < 100; ++i) same.spheres.push_back({{1, 2, 3}, 0.5f, 0, {0, 0, 0}});
    expectValidWide(same, "coincident spheres");
}

// Spheres of geometrically growing size and distance make the binary tree as deep as the
// builder allows; the collapse must then keep the deferred entries within the device stack
// (checkWide walks every path and counts them).
TEST(WideBvh, DeepTreesStayWithinTheDeviceStack) {
    Scene s = test::soup(0, 0, 5);
    for (int i = 0; i < 400; ++i) {
        float r = std::pow(1.1f, float(i % 200)) * 1e-3f;
        s.spheres.push_back({{r * 3.f * (i % 2 ? 1.f : -1.f), r, 0}, r, 0, {0, 0, 0}});
    }
    finalizeScene(s);
    expectValidWide(s, "geometric spheres");
}

TEST(WideBvh, CheckerRejectsBrokenTrees) {
    AccelData d = buildAccel(test::soup(500, 500, 6), Accel::Wide);
    ASSERT_EQ(checkWide(d), "");
    ASSERT_GT(d.wide.size(), 2u);
    AccelData shrunk = d;
    for (int k = 0; k < 4; ++k) shrunk.wide[0].hiX[k] = shrunk.wide[0].loX[k];  // flat boxes
    EXPECT_NE(checkWide(shrunk), "");
    AccelData twice = d;
    for (int k = 1; k < 4; ++k)  // two slots of the root point at one node
        if (twice.wide[0].count[k] == 0 && twice.wide[0].child[k] >= 0 &&
            twice.wide[0].count[0] == 0) {
            twice.wide[0].child[k] = twice.wide[0].child[0];
            break;
        }
    EXPECT_NE(checkWide(twice), "");
}

TEST(WideBvh, ParsedAndNamedInTheDefines) {
    EXPECT_EQ(parseAccel("wide"), Accel::Wide);
    EXPECT_STREQ(accelName(Accel::Wide), "wide");
    EXPECT_THROW(parseAccel("bvh8"), Error);
    RenderOptions o;
    o.accel = Accel::Wide;
    auto d = featureDefines(load("mesh"), o);
    EXPECT_NE(std::find(d.begin(), d.end(), "RT_ACCEL_WIDE"), d.end());
    d = featureDefines(load("empty"), o);
    EXPECT_EQ(std::find(d.begin(), d.end(), "RT_ACCEL_WIDE"), d.end());
}

// The tolerance of tests/accel_test.cpp: the traversal order only changes which of two equally
// near primitives wins, and where a slab test lets a grazing ray through.
void expectSameImage(const Image& a, const Image& b, const std::string& what) {
    ImageDiff d = compareImages(a, b, 1.0 / 255.0);
    EXPECT_GE(d.fractionWithin, 0.999)
        << what << ": " << d.pixelsOver << " pixels over 1/255, max " << d.maxAbs * 255 << "/255, "
        << countNonFinite(a) << " and " << countNonFinite(b) << " non-finite pixels";
    EXPECT_LE(d.meanAbs, 0.1 / 255.0) << what;
}

class WideImages : public ::testing::TestWithParam<std::string> {};

TEST_P(WideImages, StandardScenesMatchNone) {
    auto p = makePipeline(GetParam(), &test::device());
    for (const char* name : kScenes) {
        Scene scene = load(name);
        RenderOptions o = scene.defaults;
        o.width = 64;
        o.height = 48;
        o.bounces = std::min(o.bounces, 3);
        o.shadowSamples = std::min(o.shadowSamples, 4);
        o.aa = 1;
        o.accel = Accel::None;
        Image none = p->render(scene, o);
        o.accel = Accel::Wide;
        expectSameImage(p->render(scene, o), none, std::string(name) + " wide");
    }
}

// A soup of spheres and triangles seen from inside: rays start in many boxes, and the four
// children of a node overlap.
TEST_P(WideImages, SoupMatchesNone) {
    Scene scene = test::soup(300, 700, 7);
    scene.lights.push_back({{0, 30, 0}, 0.f, {1, 1, 1}, 0});
    scene.camera.position = {0, 0, -30};
    // A field of view (the soup leaves it 0, which makes every camera ray NaN: a frame that the
    // clamping comparison of old reported as equal to itself).
    scene.camera.fovY = 0.8f;
    scene.materials[0].diffuse = {0.7f, 0.6f, 0.5f};
    scene.materials[0].exponent = 16.f;
    auto p = makePipeline(GetParam(), &test::device());
    RenderOptions o = scene.defaults;
    o.width = 64;
    o.height = 48;
    o.bounces = 1;
    o.accel = Accel::None;
    Image none = p->render(scene, o);
    o.accel = Accel::Wide;
    expectSameImage(p->render(scene, o), none, "soup wide");
}

INSTANTIATE_TEST_SUITE_P(Pipelines, WideImages,
                         ::testing::ValuesIn(pipelineRegistry().names(true)),
                         [](const auto& info) { return info.param; });

// The small stress scenes (4,096 spheres, 20,000 triangles) into a folder of this test's own.
TEST(WideBvh, SmallStressScenesMatchNone) {
    fs::path dir = fs::path(RTLAB_BIN_DIR).parent_path() / "stress-small-wide";
    std::string cmd = "python3 scripts/make-stress.py --out " + dir.string() +
                      " --side 64 --terrain 100 > /dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    for (const char* name : {"many-spheres", "big-mesh"}) {
        Scene scene = loadScene(dir / (std::string(name) + ".json"), readImage);
        EXPECT_EQ(checkWide(buildAccel(scene, Accel::Wide)), "") << name;
        for (const std::string& kind : pipelineRegistry().names(true)) {
            RenderOptions o = scene.defaults;
            o.width = 48;
            o.height = 27;
            o.bounces = 2;
            auto p = makePipeline(kind, &test::device());
            o.accel = Accel::None;
            Image none = p->render(scene, o);
            o.accel = Accel::Wide;
            expectSameImage(p->render(scene, o), none,
                            std::string(name) + " " + kind + " wide");
        }
    }
}

}  // namespace
}  // namespace rt
