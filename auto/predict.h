// rtlab — which design a scene favours, said before any of them runs: an estimate of how busy a
// megakernel's warps would be, from the shapes of the ray trees of a sample of warps traced on
// the CPU (core/reference.h), and a rule that reads the winner from it.
//
// A work-item of the megakernel traces its pixel's whole ray tree, one ray per step of its loop,
// so a warp runs as many steps as its largest tree while the lanes of smaller trees idle. Over a
// frame the mean number of busy lanes a step is the sum of the trees' sizes over the sum of each
// warp's largest: 32 when neighbouring pixels' trees agree, a few when a mirror or a glass sphere
// gives one lane in the warp a tree of dozens of rays. The queue wavefront traces every live ray
// of a bounce in compacted launches instead, so it does not pay for that disagreement.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "auto/handout_order.h"
#include "auto/thresholds.h"
#include "core/scene.h"

namespace rt {

// The pixels one warp takes: 32 lanes of a 16x8 work-group (core/pipeline.cpp, launch2d) are 16
// columns of 2 rows.
struct WarpShape {
    int width = 16, height = 2;
    int lanes() const { return width * height; }
};

// Mean busy lanes a step: `sizes` holds the tree sizes of consecutive warps, `lanes` each.
// Empty trees (0) are lanes without work. 0 when nothing was traced.
double busyLanes(const std::vector<int>& sizes, int lanes);

struct LaneEstimate {
    double busyLanes = 0;  // of shape.lanes()
    int lanes = 32;
    int warps = 0;            // warps traced
    double raysPerPixel = 0;  // mean closest-hit rays of a pixel's trees
    int largestTree = 0;      // the largest tree of a pixel seen
    // Distinct objects the camera rays of a warp hit (a miss counts as one), the mean over warps:
    // 1 when a warp sees one object, up to 32 when its rays fetch different primitives.
    double objectsPerWarp = 0;
};

// Traces the trees of `warps` warps spread over the frame at random (a fixed seed, so the same
// scene and settings give the same estimate) and counts their busy lanes.
LaneEstimate estimateBusyLanes(const Scene& scene, const RenderOptions& options, int warps = 2048,
                               WarpShape shape = {}, std::uint64_t seed = 1, int threads = 0);

// The code a lane runs to shade a hit: its procedural pattern (RT_PATTERN_CHECKER..BUMP), or for a
// material without one plain, mirror or glass, or a miss: auto/handout_order.h's numbering and
// RT_SHADING_CODE, which the persistent schedules' sort keys share (persistent/handout.cl).
enum ShadingKey : int {
    kShadePlain = RT_PATTERN_NONE,
    kShadeMirror = RT_KEY_MIRROR,
    kShadeGlass = RT_KEY_GLASS,
    kShadeMiss = RT_KEY_MISS
};
int shadingKey(const Scene& scene, int material);

// Pixel k of a whole frame in the order the persistent megakernel hands pixels out
// (auto/handout_order.h, RT_STRIP_PIXEL, which persistent/handout.cl's Persistent_PixelOf uses):
// bands of th rows, strips of tw columns in a band (the last band and strip cut to fit), row by
// row inside a strip.
glm::ivec2 stripPixel(long long k, int width, int height, int tw = 4, int th = 16);

// How many shading keys the lanes of one warp step meet, the mean over steps, in three orders
// of the same rays: the megakernel's (a warp of 16x2 pixels, each lane tracing its own tree depth
// first), the bounce loop's (32 consecutive rays of one bounce's list, a batch of pixels in 4x16
// strips, each ray's children appended after its list's earlier rays' children), and those lists
// sorted by key before shading (--persistent-schedule bounce-staged). 1 when a warp's lanes
// run one key's code; more when it runs several in turn.
//
// And the lanes of 32 that cast shadow rays (those whose ray hit something) in a warp step that
// casts any: the megakernel's step, the bounce loop's trace (each lane right after its own
// trace, --persistent-schedule bounce), and its shadow pass (each list's hits compacted, 32 a
// step, --persistent-schedule bounce-staged).
struct ShadingEstimate {
    double megakernel = 0, bounce = 0, sorted = 0;                  // keys a warp step
    double shadowMegakernel = 0, shadowInline = 0, shadowPass = 0;  // lanes casting shadow rays
    int warps = 0, batches = 0;                                     // traced
};
ShadingEstimate estimateShadingKeys(const Scene& scene, const RenderOptions& options,
                                    int warps = 2048, int batches = 32, int batch = 1024,
                                    std::uint64_t seed = 1, int threads = 0);

// The estimate of the last scene and settings asked for, traced again only when what it depends
// on changes (the scene object, the frame's size, bounces, anti-aliasing and the intersection
// tests), so that a pipeline that chooses from it each frame traces once per scene.
class LaneEstimateCache {
  public:
    const LaneEstimate& get(const Scene& scene, const RenderOptions& options);
    // Keeps an estimate traced elsewhere (in `ms`) for these scene and settings, so that a
    // pipeline handed one by another does not trace the same warps again.
    void put(const Scene& scene, const RenderOptions& options, const LaneEstimate& estimate,
             double ms);
    double lastMs() const { return ms_; }  // CPU time of the trace the estimate came from

  private:
    struct Key {
        std::uint64_t scene = 0;
        int width = 0, height = 0, bounces = 0, aa = 0;
        bool robustSphere = false, watertight = false;
        RenderOptions::Offset offset{};
        bool operator==(const Key&) const = default;
    };
    static Key keyOf(const Scene& scene, const RenderOptions& options);
    Key key_;
    LaneEstimate estimate_;
    double ms_ = 0;
    bool valid_ = false;
};

// The rule: below `queueBelowLanes` busy lanes of 32, the queue wavefront wins; at or above it a
// design that gives each work-item a whole tree (the megakernel or the report's tree wavefront)
// does. The default is the GPU's fitted threshold (auto/thresholds.h); a CPU's is 0.
inline constexpr double kQueueBelowLanes = kGpuThresholds.queueBelowLanes;

struct Prediction {
    std::string design;  // "queue" or "tree-per-work-item"
    std::string reason;  // one sentence with the numbers
};

Prediction predictDesign(const LaneEstimate& estimate, double queueBelowLanes = kQueueBelowLanes);

}  // namespace rt
