// Wavefront pipeline: the same image as the megakernel, bit for bit, on every standard
// scene at bounce limits 0..8, with and without soft shadows and anti-aliasing; row tiling under a
// memory budget; the error when not even one row fits.
#include "wavefront/tree/wavefront.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "bench/sweep_config.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "megakernel/megakernel.h"
#include "megakernel/megakernel_options.h"
#include "test_device.h"
#include "test_scenes.h"

namespace rt {
namespace {

using test::kScenes;
using test::load;

// The global tree's size, as the pipeline reports it among its extras.
size_t treeBytes(const FrameStats& s) { return s.extras.value("tree_bytes", size_t(0)); }

// The bounce limit travels in the settings: a second limit renders with the program the first
// one built (from the context's memory), and still matches the megakernel's image.
TEST(Wavefront, OneProgramForEveryBounceLimit) {
    Scene scene = load("spheres");
    WavefrontPipeline wave(test::device());
    MegakernelPipeline mega(test::device());
    RenderOptions o = scene.defaults;
    o.width = 48;
    o.height = 32;
    o.bounces = 2;
    wave.render(scene, o);
    o.bounces = 5;
    Image a = wave.render(scene, o);
    EXPECT_EQ(wave.stats().program, "memory");
    Image b = mega.render(scene, o);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * 4), 0);
}

// Both pipelines call the same device functions (core/cl/raytree.cl) with FP_CONTRACT OFF and sum
// AA samples in the same order, so the target is bit-identical; the acceptance bound is 1e-5.
// The megakernel's tree layout is a program per bounce limit, so the bounce limits are a sample:
// no bounce, one, the first with grandchildren, a middle one and the deepest of the range.
class WaveVsMega : public ::testing::TestWithParam<const char*> {};

TEST_P(WaveVsMega, SameImageAtBounceLimitsFrom0To8) {
    Scene scene = load(GetParam());
    MegakernelPipeline mega(test::device());
    WavefrontPipeline wave(test::device());
    for (int soft = 0; soft <= 1; ++soft)
        for (int aa = 1; aa <= 2; ++aa)
            for (int b : {0, 1, 2, 5, 8}) {
                RenderOptions o = scene.defaults;
                o.width = 20;
                o.height = 15;
                o.bounces = b;
                o.aa = aa;
                o.shadowSamples = soft ? 4 : 1;
                Image m = mega.render(scene, o), w = wave.render(scene, o);
                for (float v : m.rgb) ASSERT_TRUE(std::isfinite(v)) << GetParam() << " B=" << b;
                ImageDiff d = compareImages(m, w, 1e-5, false);
                EXPECT_LE(d.maxAbs, 1e-5)
                    << GetParam() << " B=" << b << " aa=" << aa << " soft=" << soft;
                EXPECT_EQ(std::memcmp(m.rgb.data(), w.rgb.data(), m.rgb.size() * 4), 0)
                    << GetParam() << " B=" << b << " aa=" << aa << " soft=" << soft
                    << ": not bit-identical (max diff " << d.maxAbs << ")";
            }
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, WaveVsMega, ::testing::ValuesIn(kScenes));

// From B = 14 the trace kernel steps over the rest of a word of untraced parents at once
// (wavefront/tree/wavefront.cl, compiled only for such deep trees). The glass scene at B = 14
// and 15, against the weighted megakernel, which walks the same rays depth first: a traced
// parent skipped by mistake would lose its subtree and show far beyond the summation order's
// last-bit differences.
TEST(Wavefront, DeepTreeStepsOverEmptyWordsWithTheSameImage) {
    Scene scene = load("spheres");
    ASSERT_EQ(scene.branching(), 2);
    MegakernelPipeline mega(test::device());
    WavefrontPipeline wave(test::device());
    for (int b : {14, 15}) {
        RenderOptions o = scene.defaults;
        o.width = 12;
        o.height = 8;
        o.bounces = b;
        setMegaLayout(o, MegaLayout::Weighted);
        Image m = mega.render(scene, o), w = wave.render(scene, o);
        for (float v : w.rgb) ASSERT_TRUE(std::isfinite(v)) << "B=" << b;
        ImageDiff d = compareImages(m, w, 1e-5, false);
        EXPECT_LE(d.maxAbs, 1e-5) << "B=" << b;
    }
}

TEST(Wavefront, TiledFrameEqualsUntiled) {
    Scene scene = load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 40;
    o.height = 30;
    // C = 2: N = 15 nodes of 48 B and one word of traced flags, 724 B per pixel, 28,960 B a row.
    o.bounces = 3;
    EXPECT_EQ(WavefrontPipeline::pixelBytes(2, 3), size_t(15 * 48 + 4));
    WavefrontPipeline wave(test::device());
    Image whole = wave.render(scene, o);
    EXPECT_EQ(wave.stats().tiles, 1);
    EXPECT_EQ(treeBytes(wave.stats()), size_t(40 * 30 * 724));
    EXPECT_EQ(wave.stats().extras["tree_pixel_bytes"], 724);
    EXPECT_EQ(wave.stats().extras["memory_tiles"], 1);
    o.memoryBudget = 100'000;  // 3 rows per tile
    Image tiled = wave.render(scene, o);
    EXPECT_EQ(wave.stats().tiles, 10);
    EXPECT_EQ(treeBytes(wave.stats()), size_t(40 * 3 * 724));
    EXPECT_EQ(wave.stats().extras["memory_tiles"], 10);
    EXPECT_EQ(std::memcmp(whole.rgb.data(), tiled.rgb.data(), whole.rgb.size() * 4), 0);
}

// A row that alone takes longer than --max-launch-ms is launched in pieces of columns:
// with a cap no launch can meet, every row after the first probe goes in work-group-wide pieces,
// with 2x2 AA (the image kernel adds samples, so a column traced twice would show), and the
// frame keeps its bits. Three column steps of a CPU device's work-group (64) and a ragged end.
TEST(Wavefront, RowCostlierThanTheCapGoesInColumnPieces) {
    Scene scene = load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 3 * 64 + 17;
    o.height = 3;
    o.bounces = 3;
    o.aa = 2;
    WavefrontPipeline wave(test::device());
    o.maxLaunchMs = 0;
    Image whole = wave.render(scene, o);
    EXPECT_EQ(wave.stats().tiles, 1);
    o.maxLaunchMs = 1e-6;
    wave.render(scene, o);  // the first frame probes
    Image pieces = wave.render(scene, o);
    EXPECT_GT(wave.stats().tiles, o.height) << "no row was split into columns";
    EXPECT_EQ(wave.stats().launches, 3 * o.aa * o.aa * wave.stats().tiles);
    EXPECT_EQ(std::memcmp(whole.rgb.data(), pieces.rgb.data(), whole.rgb.size() * 4), 0);
}

TEST(Wavefront, BudgetBelowOneRowNamesABounceLimitThatFits) {
    Scene scene = load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 40;
    o.height = 30;
    o.bounces = 6;            // N = 127: 40 x (127 x 48 + 4 x 4) = 244,480 B per row
    o.memoryBudget = 20'000;  // B = 2 fits (N = 7: 13,600 B a row), B = 3 does not (28,960)
    WavefrontPipeline wave(test::device());
    try {
        wave.render(scene, o);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("--memory-budget"), std::string::npos) << msg;
        EXPECT_NE(msg.find("the highest bounce limit that fits is 2"), std::string::npos) << msg;
    }
    EXPECT_EQ(WavefrontPipeline::tileRows(40, 30, 2, 6, 244'480, "x"), 1);
    EXPECT_THROW(WavefrontPipeline::tileRows(40, 30, 2, 6, 244'479, "x"), Error);
    EXPECT_EQ(WavefrontPipeline::tileRows(40, 30, 1, 0, 1 << 30, "x"), 30);
}

TEST(Wavefront, StatsReportKernelsAndTreeBytes) {
    Scene scene = load("cornell");
    RenderOptions o = scene.defaults;
    o.width = 16;
    o.height = 12;
    o.bounces = 2;
    o.aa = 2;
    WavefrontPipeline wave(test::device());
    wave.render(scene, o);
    const FrameStats& s = wave.stats();
    ASSERT_EQ(s.kernelMs.size(), 3u);
    EXPECT_EQ(s.kernelMs[0].first, "trace");
    EXPECT_EQ(s.kernelMs[1].first, "image");
    EXPECT_EQ(s.kernelMs[2].first, "reset");
    for (const auto& [name, ms] : s.kernelMs) EXPECT_GT(ms, 0.0) << name;
    const size_t nodes = size_t(treeNodeCount(scene.branching(), 2));
    EXPECT_EQ(treeBytes(s), size_t(16 * 12) * (nodes * sizeof(dev::Node) + 4));
    // The buffers are named in the generic stats: the tree's payloads and its flags add up to it.
    ASSERT_GE(s.buffers.size(), 2u);
    EXPECT_EQ(s.buffers[0].first, "ray tree");
    EXPECT_EQ(s.buffers[0].second, size_t(16 * 12) * nodes * sizeof(dev::Node));
    EXPECT_EQ(s.buffers[1].first, "tree flags");
    EXPECT_EQ(s.buffers[0].second + s.buffers[1].second, treeBytes(s));
}

// The image kernel reads a node's payload only where trace set its bit this pass, and reset
// clears every bit between passes. Payloads of the last frame are filled with NaNs that also read
// as "traced" nodes (an earlier layout kept the flag inside them): if the image kernel
// read any unreached slot, or a bit survived from the last pass or sample, NaNs or stale nodes
// would reach the image, which must instead stay bit-identical to the megakernel's.
TEST(Wavefront, UnreachedPayloadsAreNeverRead) {
    Scene scene = load("spheres");  // glass: C = 2, trees of every depth
    RenderOptions o = scene.defaults;
    o.width = 40;
    o.height = 30;
    o.bounces = 6;
    o.aa = 2;
    MegakernelPipeline mega(test::device());
    WavefrontPipeline wave(test::device());
    Image expected = mega.render(scene, o);
    wave.render(scene, o);
    for (int frame = 0; frame < 2; ++frame) {
        wave.poisonPayloads();
        Image w = wave.render(scene, o);
        for (float v : w.rgb) ASSERT_TRUE(std::isfinite(v)) << "frame " << frame;
        EXPECT_EQ(std::memcmp(expected.rgb.data(), w.rgb.data(), w.rgb.size() * 4), 0)
            << "frame " << frame;
    }
}

// Every flag word is zero after a frame (the next one starts from an untraced tree), on one
// tile and on several, though each pass of these frames traced slots at every depth.
TEST(Wavefront, ResetClearsEveryFlag) {
    Scene scene = load("spheres");
    RenderOptions o = scene.defaults;
    o.width = 40;
    o.height = 30;
    o.bounces = 5;
    o.aa = 2;
    o.countRays = true;
    WavefrontPipeline wave(test::device());
    // N = 63: two flag words a pixel; 40 x 3,032 B a row, so 500,000 B hold 4 rows (8 tiles).
    for (size_t budget : {size_t(0), size_t(500'000)}) {
        o.memoryBudget = budget;
        wave.render(scene, o);
        EXPECT_EQ(wave.stats().tiles, budget ? 8 : 1);
        EXPECT_GT(wave.stats().rays[RT_RAY_REFRACTION], 0u) << "no slot below the root traced";
        std::vector<uint32_t> flags = wave.tracedFlags();
        EXPECT_EQ(flags.size(), size_t(40 * (budget ? 4 : 30) * 2));
        size_t set = 0;
        for (uint32_t w : flags) set += w != 0;
        EXPECT_EQ(set, 0u) << "of " << flags.size() << " words, budget " << budget;
    }
}

// bench/sweeps/tree-wave, the measurement of the tree layout: the headline frame (cornell
// 1920x1080, B = 8, 8 shadow samples) and the README's (spheres 1280x720, B = 8), tree wavefront
// and megakernel each, with the ray counts that give the share of slots used.
TEST(Wavefront, BenchmarkSweepHoldsTheIssuesFrame) {
    bench::SweepConfig c = bench::loadSweep(bench::findSweep("tree-wave"));
    Scene cornell = load("cornell"), spheres = load("spheres");
    std::vector<bench::Cell> cells =
        bench::expandCells(c, [&](const std::string& name) -> const Scene& {
            return name == "cornell" ? cornell : spheres;
        });
    ASSERT_EQ(cells.size(), 4u);
    int wave = 0;
    for (const bench::Cell& cell : cells) {
        wave += cell.pipeline == "wave";
        EXPECT_EQ(cell.options.bounces, 8);
        EXPECT_TRUE(cell.countRays);
    }
    EXPECT_EQ(wave, 2);
    EXPECT_EQ(cells[0].options.width, 1920);
    EXPECT_EQ(cells[0].options.height, 1080);
    EXPECT_EQ(cells[0].options.shadowSamples, 8);
}

}  // namespace
}  // namespace rt
