// Procedural materials: the noise and patterns of core/procedural.cpp against values
// derived here from their definitions, the loader's new keys, and the divergence scene rendered
// by every pipeline against the megakernel and the double-precision CPU reference.
#include "core/procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/error.h"
#include "core/kernel_resources.h"
#include "core/pipeline.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "megakernel/megakernel_options.h"
#include "pipelines/registry.h"
#include "scratch_dir.h"
#include "test_device.h"

namespace rt {
namespace {

using glm::dvec3;

// The 16 gradient directions the definition picks by hash & 15 (Perlin 2002's cube edges, with
// four repeated), written out by hand.
const dvec3 kGrad[16] = {{1, 1, 0},  {-1, 1, 0},  {1, -1, 0}, {-1, -1, 0}, {1, 0, 1},  {-1, 0, 1},
                         {1, 0, -1}, {-1, 0, -1}, {0, 1, 1},  {0, -1, 1},  {0, 1, -1}, {0, -1, -1},
                         {1, 1, 0},  {0, -1, 1},  {-1, 1, 0}, {0, -1, -1}};

TEST(Procedural, GradientIsTheDotWithTheTabledDirection) {
    const dvec3 d(0.3, -0.7, 0.45);
    for (uint32_t h = 0; h < 32; ++h)
        EXPECT_DOUBLE_EQ(proc::grad(h, d.x, d.y, d.z), glm::dot(kGrad[h & 15], d)) << h;
}

TEST(Procedural, HashOfTheOriginIsZeroAndNeighboursDiffer) {
    EXPECT_EQ(proc::hash(0, 0, 0), 0u);  // every product and shift of 0 is 0
    EXPECT_NE(proc::hash(1, 0, 0), proc::hash(0, 1, 0));
    EXPECT_NE(proc::hash(-1, 0, 0), proc::hash(1, 0, 0));
}

TEST(Procedural, FadeHasTheEndpointsAndMidpointOfItsPolynomial) {
    EXPECT_EQ(proc::fade(0), 0);
    EXPECT_EQ(proc::fade(1), 1);
    EXPECT_DOUBLE_EQ(proc::fade(0.5), 0.5);  // 6/32 - 15/16 + 10/8
    EXPECT_DOUBLE_EQ(proc::fade(0.25), 6.0 / 1024 - 15.0 / 256 + 10.0 / 64);
}

TEST(Procedural, NoiseIsZeroOnTheLattice) {
    for (int x = -3; x <= 3; ++x)
        for (int y = -3; y <= 3; ++y)
            for (int z = -3; z <= 3; ++z) EXPECT_EQ(proc::noise(dvec3(x, y, z)), 0.0);
}

// On the x edge of the cell at the origin only corners (0,0,0) and (1,0,0) count (v = w = 0),
// and fade(1/2) = 1/2: the value is the mean of their gradients' x components times +-1/2.
TEST(Procedural, NoiseMidEdgeByHand) {
    const double g0 = kGrad[proc::hash(0, 0, 0) & 15].x, g1 = kGrad[proc::hash(1, 0, 0) & 15].x;
    EXPECT_DOUBLE_EQ(proc::noise(dvec3(0.5, 0, 0)), 0.5 * (0.5 * g0) + 0.5 * (-0.5 * g1));
}

TEST(Procedural, NoiseIsBoundedContinuousAndNotFlat) {
    std::mt19937 rng(15);
    std::uniform_real_distribution<double> u(-20, 20);
    double most = 0;
    for (int i = 0; i < 20000; ++i) {
        const dvec3 p(u(rng), u(rng), u(rng));
        const double n = proc::noise(p);
        EXPECT_LE(std::fabs(n), 1.5);
        most = std::max(most, std::fabs(n));
        // Across a cell face the value moves by no more than the slope allows.
        const dvec3 q(std::floor(p.x), p.y, p.z);
        EXPECT_NEAR(proc::noise(q - dvec3(1e-9, 0, 0)), proc::noise(q + dvec3(1e-9, 0, 0)), 1e-7);
    }
    EXPECT_GT(most, 0.4);
}

TEST(Procedural, FbmSumsOctavesAtDoubledFrequencyHalvedAmplitude) {
    const dvec3 p(1.37, -0.42, 2.9);
    EXPECT_EQ(proc::fbm(p, 0, false), 0.0);
    EXPECT_EQ(proc::fbm(p, 1, false), proc::noise(p));
    EXPECT_DOUBLE_EQ(proc::fbm(p, 2, false), proc::noise(p) + 0.5 * proc::noise(2.0 * p));
    EXPECT_DOUBLE_EQ(proc::fbm(p, 2, true),
                     std::fabs(proc::noise(p)) + 0.5 * std::fabs(proc::noise(2.0 * p)));
    // 64 octaves: the later ones wrap (no lattice overflow) and weigh next to nothing.
    const double deep = proc::fbm(p * 1000.0, RT_MAX_OCTAVES, false);
    EXPECT_TRUE(std::isfinite(deep));
    EXPECT_NEAR(deep, proc::fbm(p * 1000.0, 24, false), 1e-6);
}

TEST(Procedural, PatternsStayInTheUnitInterval) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-10, 10);
    for (int pattern : {RT_PATTERN_CHECKER, RT_PATTERN_MARBLE, RT_PATTERN_WOOD, RT_PATTERN_GRANITE})
        for (int i = 0; i < 2000; ++i) {
            const double t = proc::pattern(pattern, dvec3(u(rng), u(rng), u(rng)), 6);
            EXPECT_GE(t, 0.0);
            EXPECT_LE(t, 1.0);
        }
}

TEST(Procedural, CheckerParityByHand) {
    EXPECT_EQ(proc::pattern(RT_PATTERN_CHECKER, dvec3(0.5, 0.5, 0.5), 0), 0.0);
    EXPECT_EQ(proc::pattern(RT_PATTERN_CHECKER, dvec3(1.5, 0.5, 0.5), 0), 1.0);
    EXPECT_EQ(proc::pattern(RT_PATTERN_CHECKER, dvec3(-0.5, 0.5, 0.5), 0), 1.0);  // floor = -1
    EXPECT_EQ(proc::pattern(RT_PATTERN_CHECKER, dvec3(-0.5, -0.5, 0.5), 0), 0.0);
}

TEST(Procedural, BumpLeavesTheNormalWithoutOctavesOrStrength) {
    const dvec3 n = glm::normalize(dvec3(0.2, 1, -0.3)), p(0.3, 0.7, 1.1);
    const dvec3 a = proc::bump(p, n, 0, 0.5), b = proc::bump(p, n, 4, 0.0);
    EXPECT_NEAR(glm::length(a - n), 0, 1e-15);
    EXPECT_NEAR(glm::length(b - n), 0, 1e-15);
    const dvec3 c = proc::bump(p, n, 4, 0.5);
    EXPECT_NEAR(glm::length(c), 1, 1e-12);
    EXPECT_GT(glm::length(c - n), 1e-3);
}

// A scene of one material written to a per-test file in this process's scratch folder.
Scene loadText(const std::string& materials) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::filesystem::path path = rt::test::scratchPath(std::string(info->name()) + ".json");
    std::ofstream(path) << "{\"camera\": {\"position\": [0, 1, -3]}, \"materials\": {" << materials
                        << "}}";
    struct Remove {
        std::filesystem::path p;
        ~Remove() { std::filesystem::remove(p); }
    } remove{path};
    return loadScene(path);
}

TEST(ProceduralScene, LoaderReadsThePatternKeys) {
    Scene s = loadText(
        R"("m": {"pattern": "wood", "octaves": 7, "scale": 2.5, "diffuse2": [0.1, 0.2, 0.3]})");
    ASSERT_EQ(s.materials.size(), 1u);
    EXPECT_EQ(s.materials[0].pattern, RT_PATTERN_WOOD);
    EXPECT_EQ(s.materials[0].octaves, 7);
    EXPECT_EQ(s.materials[0].patternScale, 2.5f);
    EXPECT_EQ(s.materials[0].diffuse2.z, 0.3f);
    EXPECT_TRUE(s.hasProcedural());
    EXPECT_FALSE(loadText(R"("m": {"diffuse": [1, 1, 1]})").hasProcedural());
}

TEST(ProceduralScene, LoaderRejectsBadPatternKeysInOneLine) {
    for (const char* bad :
         {R"("m": {"pattern": "plaid"})", R"("m": {"pattern": 3})",
          R"("m": {"pattern": "wood", "octaves": 65})",
          R"("m": {"pattern": "wood", "octaves": 1.5})", R"("m": {"pattern": "wood", "scale": 0})",
          R"("m": {"pattern": "bump", "bump": -1})"}) {
        try {
            loadText(bad);
            ADD_FAILURE() << "accepted " << bad;
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
            EXPECT_NE(what.find("/materials/m/"), std::string::npos) << what;
        }
    }
}

// The ptxas lines NVIDIA's build log has with -cl-nv-verbose (the format of sm_90 builds).
TEST(KernelResources, ParsesRegistersAndSpillsPerEntryFunction) {
    const std::string log =
        "ptxas info    : 0 bytes gmem\n"
        "ptxas info    : Compiling entry function 'Megakernel_Render' for 'sm_90'\n"
        "ptxas info    : Function properties for Megakernel_Render\n"
        "    48 bytes stack frame, 8 bytes spill stores, 12 bytes spill loads\n"
        "ptxas info    : Used 122 registers, 448 bytes cmem[0]\n"
        "ptxas info    : Compiling entry function 'Wavefront_Trace' for 'sm_90'\n"
        "ptxas info    : Function properties for Wavefront_Trace\n"
        "    0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n"
        "ptxas info    : Used 80 registers, 448 bytes cmem[0]\n";
    auto r = parsePtxasLog(log);
    EXPECT_EQ(r["Megakernel_Render.registers"], 122);
    EXPECT_EQ(r["Megakernel_Render.spill_stores"], 8);
    EXPECT_EQ(r["Megakernel_Render.spill_loads"], 12);
    EXPECT_EQ(r["Megakernel_Render.stack_bytes"], 48);
    EXPECT_EQ(r["Wavefront_Trace.registers"], 80);
    EXPECT_TRUE(parsePtxasLog("PoCL says nothing of the sort").empty());
}

Scene divergence() { return loadScene("scenes/divergence.json", readImage); }

RenderOptions tiny(const Scene& scene, int bounces) {
    RenderOptions o = scene.defaults;
    o.width = 80;
    o.height = 45;
    o.bounces = bounces;
    o.aa = 1;
    return o;
}

// The accuracy bar of MegaVsCpu (tests/megakernel_test.cpp): >= 99.9% of pixels within 2/255,
// mean absolute error <= 0.5/255, on the scene where every pixel's neighbour shades differently.
TEST(ProceduralScene, MegakernelMatchesTheCpuReference) {
    Scene deep = loadScene("scenes/divergence/divergence-o64-m16.json", readImage);
    RenderOptions o64 = tiny(deep, 1);
    auto mega64 = makePipeline("mega", &test::device());
    ImageDiff d64 =
        compareImages(mega64->render(deep, o64), renderReference(deep, o64), 2.0 / 255.0);
    EXPECT_GE(d64.fractionWithin, 0.999) << "64 octaves: max " << d64.maxAbs * 255 << "/255";
    Scene scene = divergence();
    for (int bounces : {0, 3}) {
        RenderOptions o = tiny(scene, bounces);
        auto mega = makePipeline("mega", &test::device());
        ImageDiff d = compareImages(mega->render(scene, o), renderReference(scene, o), 2.0 / 255.0);
        EXPECT_GE(d.fractionWithin, 0.999) << "B=" << bounces << ": " << d.pixelsOver
                                           << " pixels over, max " << d.maxAbs * 255 << "/255";
        EXPECT_LE(d.meanAbs, 0.5 / 255.0) << "B=" << bounces;
    }
}

// Same functions, same image: the tree wavefront bit for bit with the tree megakernel, the queue
// within 1e-5 of the weighted megakernel (their sums differ in order where glass branches).
TEST(ProceduralScene, EveryPipelineGivesTheMegakernelsImage) {
    Scene scene = divergence();
    RenderOptions o = tiny(scene, 3);
    auto mega = makePipeline("mega", &test::device());
    Image tree = mega->render(scene, o);
    auto wave = makePipeline("wave", &test::device());
    EXPECT_EQ(compareImages(tree, wave->render(scene, o), 0.0, false).maxAbs, 0.0);
    setMegaLayout(o, MegaLayout::Weighted);
    Image weighted = mega->render(scene, o);
    auto queue = makePipeline("queue", &test::device());
    EXPECT_LE(compareImages(weighted, queue->render(scene, o), 1e-5, false).maxAbs, 1e-5);
    EXPECT_LE(compareImages(tree, weighted, 1e-5, false).maxAbs, 1e-5);
    const FrameStats& s = queue->stats();
    EXPECT_TRUE(std::any_of(s.kernelMs.begin(), s.kernelMs.end(), [](const auto& k) {
        return k.first == "shade procedural";
    })) << "procedural rays get their own launch";
    EXPECT_FALSE(mega->stats().kernelResources.empty()) << "private bytes at least";
}

}  // namespace
}  // namespace rt
