// The warp estimate of auto/predict.h: the busy-lane arithmetic, the CPU's tree sizes against the
// rays a device pipeline counts, and the rule.
#include "auto/predict.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <utility>
#include <vector>

#include "core/reference.h"
#include "megakernel/megakernel_options.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_scenes.h"

namespace rt {
namespace {

// Every pixel of the frame, row by row.
std::vector<glm::ivec2> framePixels(const RenderOptions& o) {
    std::vector<glm::ivec2> pixels;
    for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) pixels.push_back({x, y});
    return pixels;
}

TEST(BusyLanes, AWarpRunsAsLongAsItsLargestTree) {
    std::vector<int> even(32, 1);
    EXPECT_DOUBLE_EQ(busyLanes(even, 32), 32.0);
    // One lane with a tree of 5 rays, 31 with one: 36 rays over 5 steps.
    std::vector<int> one(32, 1);
    one[7] = 5;
    EXPECT_DOUBLE_EQ(busyLanes(one, 32), 36.0 / 5.0);
    // Warps are weighted by their steps: (32 + 36) rays over (1 + 5) steps.
    std::vector<int> both = even;
    both.insert(both.end(), one.begin(), one.end());
    EXPECT_DOUBLE_EQ(busyLanes(both, 32), 68.0 / 6.0);
    // Lanes without a pixel trace nothing.
    std::vector<int> half(32, 0);
    std::fill(half.begin(), half.begin() + 16, 2);
    EXPECT_DOUBLE_EQ(busyLanes(half, 32), 16.0);
    EXPECT_DOUBLE_EQ(busyLanes({}, 32), 0.0);
}

// The CPU traces the trees the device traces: over every pixel, the sizes add up to the camera,
// reflection and refraction rays the weighted megakernel counts.
TEST(RayTreeSizes, AddUpToTheRaysADeviceCounts) {
    for (const char* name : {"spheres", "cornell"}) {
        SCOPED_TRACE(name);
        const Scene scene = test::load(name);
        RenderOptions o = scene.defaults;
        o.width = 48, o.height = 32, o.bounces = 4, o.aa = 2;
        const std::vector<glm::ivec2> pixels = framePixels(o);
        const std::vector<int> sizes = referenceRayTreeSizes(scene, o, pixels, 2);
        const long long cpu = std::accumulate(sizes.begin(), sizes.end(), 0LL);

        o.countRays = true;
        setMegaLayout(o, MegaLayout::Weighted);
        auto mega = makePipeline("mega", &test::device());
        mega->render(scene, o);
        const RayCounts& r = mega->stats().rays;
        const long long device =
            (long long)(r[RT_RAY_PRIMARY] + r[RT_RAY_REFLECTION] + r[RT_RAY_REFRACTION]);
        EXPECT_GT(r[RT_RAY_REFLECTION], 0u);
        EXPECT_EQ(cpu, device);
        EXPECT_GT(cpu, (long long)pixels.size() * 4) << "no secondary rays to count";
    }
}

TEST(LaneEstimate, WallsWithoutMirrorsKeepEveryLaneBusy) {
    // The empty scene: every camera ray misses, a tree of one ray a pixel.
    const Scene scene = test::load("empty");
    RenderOptions o = scene.defaults;
    o.width = 64, o.height = 20;
    const LaneEstimate e = estimateBusyLanes(scene, o, 1000);
    EXPECT_EQ(e.warps, 4 * 10);  // every warp of a small frame
    EXPECT_DOUBLE_EQ(e.busyLanes, 32.0);
    EXPECT_DOUBLE_EQ(e.raysPerPixel, 1.0);
    EXPECT_EQ(e.largestTree, 1);
    EXPECT_EQ(predictDesign(e).design, "tree-per-work-item");
}

TEST(LaneEstimate, AFrameThatEndsInsideAWarpLeavesItsLanesIdle) {
    const Scene scene = test::load("empty");
    RenderOptions o = scene.defaults;
    o.width = 8, o.height = 2;  // half of one 16x2 warp
    const LaneEstimate e = estimateBusyLanes(scene, o, 16);
    EXPECT_EQ(e.warps, 1);
    EXPECT_DOUBLE_EQ(e.busyLanes, 16.0);
}

TEST(LaneEstimate, TheSameSceneGivesTheSameEstimate) {
    const Scene scene = test::load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 160, o.height = 120;
    const LaneEstimate a = estimateBusyLanes(scene, o, 50);
    const LaneEstimate b = estimateBusyLanes(scene, o, 50);
    EXPECT_EQ(a.warps, 50);
    EXPECT_DOUBLE_EQ(a.busyLanes, b.busyLanes);
    EXPECT_GT(a.busyLanes, 0.0);
    EXPECT_LE(a.busyLanes, 32.0);
    EXPECT_GT(a.largestTree, 1) << "the spheres scene has mirrors";
}

// The cache traces again when a setting the trees depend on changes, and gives back what it
// traced for the settings asked for.
TEST(LaneEstimate, TheCacheFollowsTheSettings) {
    const Scene scene = test::load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 64, o.height = 32;
    o.bounces = 4;
    LaneEstimateCache cache;
    const LaneEstimate four = cache.get(scene, o);
    EXPECT_GT(four.largestTree, 1) << "mirrors and glass branch";
    o.bounces = 0;
    EXPECT_EQ(cache.get(scene, o).largestTree, 1) << "no bounces: a camera ray a tree";
    o.bounces = 4;
    EXPECT_DOUBLE_EQ(cache.get(scene, o).busyLanes, four.busyLanes);
    const Scene other = test::load("empty");
    EXPECT_EQ(cache.get(other, o).busyLanes, 32.0) << "a new scene is traced, not the last one";
    EXPECT_GE(cache.lastMs(), 0.0);
}

// A pixel's tree node by node: as many rays as referenceRayTreeSizes counts (one AA sample), each
// child one bounce deeper than its ray, and a reflection right after its ray (depth first).
TEST(RayTreeNodes, HoldEveryRayOfThePixelsTreesDepthFirst) {
    const Scene scene = test::load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 40, o.height = 30, o.bounces = 4, o.aa = 1;
    const std::vector<glm::ivec2> pixels = framePixels(o);
    const std::vector<int> sizes = referenceRayTreeSizes(scene, o, pixels, 2);
    const auto trees = referenceRayTreeNodes(scene, o, pixels, 2);
    ASSERT_EQ(trees.size(), pixels.size());
    int branching = 0;
    for (std::size_t i = 0; i < trees.size(); ++i) {
        ASSERT_EQ(int(trees[i].size()), sizes[i]) << "pixel " << i;
        EXPECT_EQ(trees[i][0].depth, 0);
        for (std::size_t n = 0; n < trees[i].size(); ++n) {
            const RayTreeNode& node = trees[i][n];
            if (node.reflected >= 0) EXPECT_EQ(node.reflected, int(n) + 1);
            for (int child : {node.reflected, node.refracted})
                if (child >= 0) EXPECT_EQ(trees[i][std::size_t(child)].depth, node.depth + 1);
            if (node.material < 0) EXPECT_TRUE(node.reflected < 0 && node.refracted < 0);
            branching += node.reflected >= 0 && node.refracted >= 0;
        }
    }
    EXPECT_GT(branching, 0) << "no ray with both children to check";
}

// The persistent megakernel's strips: every pixel once, a 4x16 strip row by row first, and a
// frame whose last band and strip are cut.
TEST(StripPixel, VisitsEveryPixelOnceStripByStrip) {
    EXPECT_EQ(stripPixel(0, 64, 32), glm::ivec2(0, 0));
    EXPECT_EQ(stripPixel(3, 64, 32), glm::ivec2(3, 0));
    EXPECT_EQ(stripPixel(4, 64, 32), glm::ivec2(0, 1));
    EXPECT_EQ(stripPixel(63, 64, 32), glm::ivec2(3, 15));
    EXPECT_EQ(stripPixel(64, 64, 32), glm::ivec2(4, 0));
    for (const auto& [w, h] : {std::pair{64, 32}, {37, 23}}) {
        std::vector<int> seen(std::size_t(w * h), 0);
        for (long long k = 0; k < (long long)w * h; ++k) {
            const glm::ivec2 p = stripPixel(k, w, h);
            ASSERT_TRUE(p.x >= 0 && p.x < w && p.y >= 0 && p.y < h) << k;
            ++seen[std::size_t(p.y * w + p.x)];
        }
        EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), w * h) << w << "x" << h;
    }
    EXPECT_EQ(stripPixel(36 * 16, 37, 23), glm::ivec2(36, 0));  // the cut strip, 1 wide
    EXPECT_EQ(stripPixel(37 * 16, 37, 23), glm::ivec2(0, 16));  // the cut band, 7 rows
}

TEST(ShadingKeys, APatternElseTheClassElseAMiss) {
    Scene scene;
    scene.materials.resize(5);
    scene.materials[1].reflectance = 0.5f;
    scene.materials[2].opacity = 0.5f;
    scene.materials[3].pattern = RT_PATTERN_MARBLE;
    scene.materials[4].pattern = RT_PATTERN_CHECKER;
    scene.materials[4].opacity = 0.5f;  // a pattern decides before the class
    for (auto& m : scene.materials)
        if (m.opacity == 0.0f) m.opacity = 1.0f;
    EXPECT_EQ(shadingKey(scene, 0), kShadePlain);
    EXPECT_EQ(shadingKey(scene, 1), kShadeMirror);
    EXPECT_EQ(shadingKey(scene, 2), kShadeGlass);
    EXPECT_EQ(shadingKey(scene, 3), RT_PATTERN_MARBLE);
    EXPECT_EQ(shadingKey(scene, 4), RT_PATTERN_CHECKER);
    EXPECT_EQ(shadingKey(scene, -1), kShadeMiss);
}

// Where every ray misses, every warp step in every order runs one key's code and casts no shadow
// ray; elsewhere between one and all nine keys, the same for the same scene and settings.
TEST(ShadingKeys, OneKeyWhereEveryRayMisses) {
    const Scene empty = test::load("empty");
    RenderOptions o = empty.defaults;
    o.width = 64, o.height = 48;
    const ShadingEstimate e = estimateShadingKeys(empty, o, 64, 4, 256);
    EXPECT_DOUBLE_EQ(e.megakernel, 1.0);
    EXPECT_DOUBLE_EQ(e.bounce, 1.0);
    EXPECT_DOUBLE_EQ(e.sorted, 1.0);
    EXPECT_EQ(e.warps, 64);
    EXPECT_EQ(e.batches, 4);
    for (double lanes : {e.shadowMegakernel, e.shadowInline, e.shadowPass})
        EXPECT_EQ(lanes, 0.0) << "no hit, no shadow ray";

    const Scene spheres = test::load("spheres");
    o = spheres.defaults;
    o.width = 64, o.height = 48;
    const ShadingEstimate s = estimateShadingKeys(spheres, o, 64, 4, 256);
    for (double keys : {s.megakernel, s.bounce, s.sorted}) {
        EXPECT_GE(keys, 1.0);
        EXPECT_LE(keys, 9.0);
    }
    EXPECT_GT(s.bounce, 1.0) << "a wall of spheres with mirrors: lists that mix keys";
    // A shadow pass takes a list's hits 32 at a time: no fewer lanes a step than the trace's
    // steps, whose hits are spread over at least as many steps.
    EXPECT_GT(s.shadowInline, 0.0);
    EXPECT_GE(s.shadowPass, s.shadowInline);
    EXPECT_LE(s.shadowPass, 32.0);
    const ShadingEstimate again = estimateShadingKeys(spheres, o, 64, 4, 256);
    EXPECT_EQ(again.megakernel, s.megakernel);
    EXPECT_EQ(again.bounce, s.bounce);
    EXPECT_EQ(again.sorted, s.sorted);
}

TEST(Predict, TheRuleSplitsAtTheThreshold) {
    LaneEstimate e;
    e.lanes = 32;
    e.busyLanes = kQueueBelowLanes - 0.1;
    EXPECT_EQ(predictDesign(e).design, "queue");
    e.busyLanes = kQueueBelowLanes;
    EXPECT_EQ(predictDesign(e).design, "tree-per-work-item");
    e.busyLanes = 10;
    EXPECT_EQ(predictDesign(e, 8).design, "tree-per-work-item");
    EXPECT_NE(predictDesign(e).reason.find("10.0 busy lanes of 32"), std::string::npos)
        << predictDesign(e).reason;
}

}  // namespace
}  // namespace rt
