// Queue wavefront, --queue-shade: one shade launch per material class, per procedural pattern,
// or one over the hits sorted by material. The modes change which rays share a launch, never
// the arithmetic of a ray, so every mode must give the class mode's image bit for bit and the
// same rays; and each must run the launches it claims: a queue per pattern, a sort, no launch
// for a queue no material can fill.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include "bench/sweep_config.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "image/image_io.h"
#include "megakernel/megakernel_options.h"
#include "scratch_dir.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"
#include "wavefront/queue/queue.h"
#include "wavefront/queue/queue_layout.h"

namespace rt {
namespace {

using test::load;
using test::sameBits;

// A wall of 192 spheres, 4 px across at 64x48, of 16 materials at random (scripts/make-map.py):
// all five patterns, mirrors and glass side by side, so that neighbouring rays differ.
Scene mapWall() { return test::mapWall(4, "0.5", 8, "64x48"); }

RenderOptions small(const Scene& scene) {
    RenderOptions o = scene.defaults;
    o.width = 64;
    o.height = 48;
    o.bounces = 4;
    o.aa = 1;
    o.countRays = true;
    return o;
}

struct Frame {
    Image image;
    FrameStats stats;
    QueueStats queue;
};

Frame render(const Scene& scene, RenderOptions o, QueueShadeMode mode) {
    QueuePipeline queue(test::device());
    setQueueShade(o, mode);
    Image image = queue.render(scene, o);
    return {image, queue.stats(), queue.queueStats()};
}

// Frames of `scene` under options `o` in the pattern and sort modes against the class mode's.
void expectSameAsClass(const Scene& scene, const RenderOptions& o, const std::string& what) {
    const Frame base = render(scene, o, QueueShadeMode::Class);
    for (QueueShadeMode mode : {QueueShadeMode::Pattern, QueueShadeMode::Sort}) {
        const std::string label = what + ", " + queueShadeName(mode);
        const Frame f = render(scene, o, mode);
        EXPECT_TRUE(sameBits(base.image, f.image)) << label;
        EXPECT_EQ(base.stats.rays, f.stats.rays) << label;
        EXPECT_EQ(base.queue.queueLengths, f.queue.queueLengths) << label;
    }
}

// Procedural patterns, mirrors and glass (the divergence scene and a map wall), and the glass and
// mirrors of the standard scenes; launches sized by read-backs and on the device.
TEST(QueueShade, EveryModeGivesTheClassImageBitForBit) {
    for (const Scene& scene : {loadScene("scenes/divergence.json", readImage), mapWall(),
                               load("cornell"), load("spheres")}) {
        for (QueueLaunchMode launch : {QueueLaunchMode::Readback, QueueLaunchMode::Device}) {
            RenderOptions o = small(scene);
            setQueueLaunch(o, launch);
            expectSameAsClass(scene, o, scene.name + ", " + queueLaunchName(launch));
        }
    }
}

// Paths cut for room and started again, two AA samples and shadow samples, launches in pieces
// (--max-launch-ms, priced per item so that any device splits them alike), and extend in packets:
// the other ways the queues are filled and walked.
TEST(QueueShade, EveryModeGivesTheClassImageWhenQueuesAreCutSplitOrPacketed) {
    Scene wall = mapWall();
    RenderOptions o = small(wall);
    o.aa = 2;
    o.shadowSamples = 2;
    setQueuePool(o, 64);
    EXPECT_GT(render(wall, o, QueueShadeMode::Class).queue.restartedPaths, 0);
    expectSameAsClass(wall, o, "pool 64");

    o = small(wall);
    const int whole = render(wall, o, QueueShadeMode::Class).stats.launches;
    o.maxLaunchMs = 1;
    auto split = [&](QueueShadeMode mode) {
        QueuePipeline queue(test::device());
        queue.setFakeItemMsForTest(0.01);  // 100 items per 1 ms launch: every queue in pieces
        setQueueShade(o, mode);
        Frame f{queue.render(wall, o), queue.stats(), queue.queueStats()};
        EXPECT_GT(f.stats.launches, 2 * whole) << queueShadeName(mode);
        return f;
    };
    const Frame base = split(QueueShadeMode::Class);
    for (QueueShadeMode mode : {QueueShadeMode::Pattern, QueueShadeMode::Sort})
        EXPECT_TRUE(sameBits(base.image, split(mode).image)) << queueShadeName(mode);

    Scene divergence = loadScene("scenes/divergence.json", readImage);  // quads: triangles
    o = small(divergence);
    o.accel = RenderOptions::Accel::Wide;
    setQueuePackets(o, QueuePacketMode::On);
    expectSameAsClass(divergence, o, "packets");
}

// Whether the frame launched the stage `stage` ("shade marble") at all.
bool ran(const FrameStats& s, const std::string& stage) {
    return std::any_of(s.kernelMs.begin(), s.kernelMs.end(),
                       [&](const auto& kernel) { return kernel.first == stage; });
}

// The queues each mode claims. Pattern: the procedural class's rays in one queue per pattern,
// at least two of them filled; sort: every hit in the one sorted queue. Launch counts follow.
TEST(QueueShade, EachModeRunsTheQueuesItClaims) {
    Scene scene = mapWall();
    RenderOptions o = small(scene);
    const Frame cls = render(scene, o, QueueShadeMode::Class);
    const Frame pat = render(scene, o, QueueShadeMode::Pattern);
    const Frame srt = render(scene, o, QueueShadeMode::Sort);
    const auto& c = cls.queue.shadeQueueRays;
    ASSERT_GT(c[RT_Q_PROCEDURAL], 0);

    long long patterned = 0;
    int filled = 0;
    for (int p = RT_PATTERN_CHECKER; p <= RT_PATTERN_BUMP; ++p) {
        const long long n = pat.queue.shadeQueueRays[RT_Q_PATTERN_QUEUE(p)];
        patterned += n;
        filled += n > 0;
    }
    EXPECT_GE(filled, 2) << "the wall must mix patterns for the pattern mode to split them";
    EXPECT_EQ(patterned, c[RT_Q_PROCEDURAL]);
    for (int k = RT_Q_MISS; k < RT_Q_PROCEDURAL; ++k) EXPECT_EQ(pat.queue.shadeQueueRays[k], c[k]);
    EXPECT_FALSE(ran(pat.stats, "shade procedural"));
    for (const char* stage :
         {"shade checker", "shade marble", "shade wood", "shade granite", "shade bump"})
        EXPECT_TRUE(ran(pat.stats, stage)) << stage;
    // Five pattern kernels for the one procedural kernel, every bounce.
    EXPECT_EQ(pat.stats.launches - cls.stats.launches, cls.queue.iterations * 4);

    EXPECT_EQ(srt.queue.shadeQueueRays[RT_Q_MISS], c[RT_Q_MISS]);
    EXPECT_EQ(srt.queue.shadeQueueRays[RT_Q_HITS],
              c[RT_Q_DIFFUSE] + c[RT_Q_MIRROR] + c[RT_Q_GLASS] + c[RT_Q_PROCEDURAL]);
    for (const char* stage : {"sort count", "sort buckets", "sort scatter", "shade sorted"})
        EXPECT_TRUE(ran(srt.stats, stage)) << stage;
    for (const char* stage : {"shade diffuse", "shade mirror", "shade glass", "shade procedural"})
        EXPECT_FALSE(ran(srt.stats, stage)) << stage;
    // Miss, the sort's three kernels and one shade launch, against the five classes' launches.
    EXPECT_EQ(srt.stats.launches, cls.stats.launches);
    EXPECT_EQ(srt.stats.extras.at("queue_shade"), "sort");
    EXPECT_GT(srt.stats.extras.at("shade_ms").get<double>(), 0.0);
}

// The wall with a material of its own for every sphere (copies of the ones it had): ids past
// the sort's per-work-group counts (RT_Q_SORT_LOCAL_KEYS, queue_sort.cl), which go straight to
// the global ones.
Scene wallOfManyMaterials() {
    Scene scene = mapWall();
    for (dev::Sphere& s : scene.spheres) {
        scene.materials.push_back(scene.materials[size_t(s.material)]);
        scene.materialNames.push_back("copy");
        s.material = int(scene.materials.size()) - 1;
    }
    return scene;
}

// The sort mode's hit queue runs material by material: the ids never decrease along it, and it
// holds every hit of the bounce once. One bounce (B = 0), so that the queue left on the device is
// that of the camera rays, which the class mode counts by class.
TEST(QueueShade, SortedHitQueueRunsMaterialByMaterial) {
    for (const auto& [scene, least] :
         {std::pair{mapWall(), size_t(8)}, std::pair{wallOfManyMaterials(), size_t(100)}}) {
        RenderOptions o = small(scene);
        o.bounces = 0;
        const Frame cls = render(scene, o, QueueShadeMode::Class);
        QueuePipeline queue(test::device());
        setQueueShade(o, QueueShadeMode::Sort);
        EXPECT_TRUE(sameBits(cls.image, queue.render(scene, o)));
        const std::vector<int> materials = queue.sortedMaterialsForTest();
        const auto& c = cls.queue.shadeQueueRays;
        EXPECT_EQ((long long)(materials.size()),
                  c[RT_Q_DIFFUSE] + c[RT_Q_MIRROR] + c[RT_Q_GLASS] + c[RT_Q_PROCEDURAL]);
        EXPECT_TRUE(std::is_sorted(materials.begin(), materials.end()));
        std::vector<int> distinct = materials;
        distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
        EXPECT_GE(distinct.size(), least) << scene.materials.size() << " materials";
    }
}

// A queue that no material of the scene can fill costs no launch: the standard scenes have no
// pattern, so the pattern mode launches what the class mode does.
TEST(QueueShade, QueuesNoMaterialFillsAreNotLaunched) {
    for (const char* name : {"cornell", "spheres", "empty"}) {
        Scene scene = load(name);
        RenderOptions o = small(scene);
        const Frame cls = render(scene, o, QueueShadeMode::Class);
        const Frame pat = render(scene, o, QueueShadeMode::Pattern);
        EXPECT_EQ(pat.stats.launches, cls.stats.launches) << name;
        EXPECT_FALSE(ran(pat.stats, "shade checker")) << name;
    }
}

// bench/sweeps/queue-shade: the map walls and the standard scenes, the queue in each shade mode
// and the weighted megakernel, at 1920x1080 and B = 4 through the binary BVH.
TEST(QueueShade, SweepCoversEveryModeAndTheWeightedMegakernel) {
    bench::SweepConfig c = bench::loadSweep(bench::findSweep("queue-shade"));
    Scene cornell = load("cornell");
    std::vector<bench::Cell> cells =
        bench::expandCells(c, [&](const std::string&) -> const Scene& { return cornell; });
    std::map<std::string, int> queue;
    int weighted = 0;
    for (const bench::Cell& cell : cells) {
        if (cell.pipeline == "queue") ++queue[queueShadeName(queueShade(cell.options))];
        weighted += cell.pipeline == "mega" && megaLayout(cell.options) == MegaLayout::Weighted;
        EXPECT_EQ(cell.options.width, 1920);
        EXPECT_EQ(cell.options.height, 1080);
        EXPECT_EQ(cell.options.bounces, 4);
        EXPECT_EQ(cell.options.accel, RenderOptions::Accel::Bvh);
    }
    EXPECT_EQ(queue, (std::map<std::string, int>{{"class", 8}, {"pattern", 8}, {"sort", 8}}));
    EXPECT_EQ(weighted, 8);
}

}  // namespace
}  // namespace rt
