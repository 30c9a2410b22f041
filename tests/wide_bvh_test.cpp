// The wide BVHs, --accel wide (4-wide) and --accel cwbvh (compressed 8-wide): the
// collapsed trees' invariants on the host (checkWide, checkCwbvh: every primitive in one leaf,
// every decoded box on its path holding it, the device stack never overflowing), and images that
// match --accel none with every pipeline (their hits ray by ray: tests/accel_trace_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
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

// The layouts under test, and each one's checker.
constexpr Accel kWide[] = {Accel::Wide, Accel::Cwbvh};

std::string check(const AccelData& d, Accel a) {
    return a == Accel::Wide ? checkWide(d) : checkCwbvh(d);
}

size_t nodeCount(const AccelData& d, Accel a) {
    return a == Accel::Wide ? d.wide.size() : d.cwbvh.size();
}

void expectValidWide(const Scene& scene, const std::string& name) {
    for (Accel a : kWide) {
        AccelData d = buildAccel(scene, a);
        std::string what = name + " " + accelName(a);
        EXPECT_EQ(check(d, a), "") << what;
        EXPECT_EQ(checkBvh(d), "") << what;  // the binary tree it came from
        EXPECT_EQ(d.stats.nodes, (long long)nodeCount(d, a)) << what;
        EXPECT_EQ(d.stats.name, accelName(a));
        if (d.bvh.size() > 1) EXPECT_LT(nodeCount(d, a), d.bvh.size() / 2) << what;
    }
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
// (the checkers walk every path and count them).
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

TEST(Cwbvh, CheckerRejectsBrokenTrees) {
    AccelData d = buildAccel(test::soup(500, 500, 6), Accel::Cwbvh);
    ASSERT_EQ(checkCwbvh(d), "");
    ASSERT_GT(d.cwbvh.size(), 2u);
    AccelData flat = d;
    for (int k = 0; k < 8; ++k)
        if (flat.cwbvh[0].loX[k] != 255) flat.cwbvh[0].hiX[k] = flat.cwbvh[0].loX[k];
    EXPECT_NE(checkCwbvh(flat), "");
    // A leaf entry whose vertex is not its triangle's, and two leaves sharing entries.
    AccelData moved = d;
    for (dev::CwbvhPrim& p : moved.cwbvhPrims)
        if (p.ref >= 0) {
            p.v1.x += 1e-3f;
            break;
        }
    EXPECT_NE(checkCwbvh(moved), "");
    AccelData shared = d;
    for (dev::CwbvhNode& n : shared.cwbvh) {
        int leaves[2], m = 0;
        for (int k = 0; k < 8 && m < 2; ++k)
            if (!(n.innerMask >> k & 1) && n.loX[k] <= n.hiX[k]) leaves[m++] = k;
        if (m == 2) {
            n.meta[leaves[1]] = n.meta[leaves[0]];
            break;
        }
    }
    EXPECT_NE(checkCwbvh(shared), "");
}

// Eight spheres at the corners of a cube: the root's slot k holds the one at corner k (bit a of
// k set: the + side of axis a), the order a ray visits them in without sorting.
TEST(Cwbvh, ChildrenSitInTheSlotOfTheirCorner) {
    Scene s = test::soup(0, 0, 8);
    for (int k = 0; k < 8; ++k)
        s.spheres.push_back(
            {{k & 1 ? 5.f : -5.f, k & 2 ? 5.f : -5.f, k & 4 ? 5.f : -5.f}, 1.f, 0, {0, 0, 0}});
    finalizeScene(s);
    AccelData d = buildAccel(s, Accel::Cwbvh);
    ASSERT_EQ(checkCwbvh(d), "");
    const dev::CwbvhNode& root = d.cwbvh.at(0);
    EXPECT_EQ(cwbvhChildren(root), 8);
    EXPECT_EQ(cwbvhChildren(buildAccel(test::soup(0, 1, 3), Accel::Cwbvh).cwbvh.at(0)), 1);
    for (int k = 0; k < 8; ++k) {
        ASSERT_FALSE(root.innerMask >> k & 1) << "slot " << k;
        ASSERT_EQ(root.meta[k] >> 5, 0) << "slot " << k << " holds one sphere";
        const dev::CwbvhPrim& p = d.cwbvhPrims.at(size_t(root.primBase + (root.meta[k] & 31)));
        ASSERT_LT(p.ref, 0);
        const dev::Float3& c = d.spheres.at(size_t(sphereRef(p.ref))).center;
        EXPECT_EQ((c.x > 0 ? 1 : 0) | (c.y > 0 ? 2 : 0) | (c.z > 0 ? 4 : 0), k);
    }
}

// A leaf longer than a slot holds (the binary builder's depth cap can leave one) is cut into
// slots of at most eight, and what does not fit the node's 32 entries goes one node down.
TEST(Cwbvh, LongLeavesAreCutIntoSlots) {
    AccelData d = buildAccel(test::soup(0, 300, 9), Accel::Bvh);
    d.bvh.resize(1);
    d.bvh[0].first = 0;
    d.bvh[0].count = int(d.triangles.size());
    buildCwbvh(d);
    EXPECT_EQ(checkCwbvh(d), "");
    EXPECT_GE(d.cwbvh.size(), 300u / 32u);
    for (const dev::CwbvhNode& n : d.cwbvh) EXPECT_LE(std::popcount(unsigned(n.innerMask)), 1);
}

TEST(WideBvh, ParsedAndNamedInTheDefines) {
    EXPECT_EQ(parseAccel("wide"), Accel::Wide);
    EXPECT_STREQ(accelName(Accel::Wide), "wide");
    EXPECT_EQ(parseAccel("cwbvh"), Accel::Cwbvh);
    EXPECT_STREQ(accelName(Accel::Cwbvh), "cwbvh");
    EXPECT_THROW(parseAccel("bvh8"), Error);
    for (auto [a, define] :
         {std::pair{Accel::Wide, "RT_ACCEL_WIDE"}, {Accel::Cwbvh, "RT_ACCEL_CWBVH"}}) {
        RenderOptions o;
        o.accel = a;
        auto d = featureDefines(load("mesh"), o);
        EXPECT_NE(std::find(d.begin(), d.end(), define), d.end());
        d = featureDefines(load("empty"), o);
        EXPECT_EQ(std::find(d.begin(), d.end(), define), d.end());
    }
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

// Every pipeline through both wide layouts, on the scenes with every kind of object the layouts
// hold (cornell: triangles and spheres; mesh: a model's mesh). The layouts' hits on every scene
// are tested ray by ray in tests/accel_trace_test.cpp.
class WideImages : public ::testing::TestWithParam<std::tuple<std::string, Accel>> {};

TEST_P(WideImages, SceneImagesMatchNone) {
    auto [kind, accel] = GetParam();
    auto p = makePipeline(kind, &test::device());
    for (const char* name : {"cornell", "mesh"}) {
        Scene scene = load(name);
        RenderOptions o = scene.defaults;
        o.width = 64;
        o.height = 48;
        o.bounces = std::min(o.bounces, 3);
        o.shadowSamples = std::min(o.shadowSamples, 4);
        o.aa = 1;
        o.accel = Accel::None;
        Image none = p->render(scene, o);
        o.accel = accel;
        expectSameImage(p->render(scene, o), none, std::string(name) + " " + accelName(accel));
    }
}

INSTANTIATE_TEST_SUITE_P(Pipelines, WideImages,
                         ::testing::Combine(::testing::ValuesIn(pipelineRegistry().names(true)),
                                            ::testing::ValuesIn(kWide)),
                         [](const auto& info) {
                             return std::get<0>(info.param) + "_" +
                                    accelName(std::get<1>(info.param));
                         });

// The small stress scenes (4,096 spheres, 20,000 triangles), into a folder of this test's own:
// both layouts keep their invariants on scenes of that size.
TEST(WideBvh, SmallStressScenesKeepTheInvariants) {
    fs::path dir = fs::path(RTLAB_BIN_DIR).parent_path() / "stress-small-wide";
    std::string cmd = "python3 scripts/make-stress.py --out " + dir.string() +
                      " --side 64 --terrain 100 > /dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    for (const char* name : {"many-spheres", "big-mesh"}) {
        Scene scene = loadScene(dir / (std::string(name) + ".json"), readImage);
        for (Accel a : kWide) EXPECT_EQ(check(buildAccel(scene, a), a), "") << name;
    }
}

}  // namespace
}  // namespace rt
