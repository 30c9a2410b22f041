// rtlab — the warp estimate and the rule of core/predict.h.
#include "core/predict.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <random>

#include "core/error.h"
#include "core/reference.h"

namespace rt {

double busyLanes(const std::vector<int>& sizes, int lanes) {
    long long rays = 0, steps = 0;
    for (std::size_t w = 0; w < sizes.size(); w += std::size_t(lanes)) {
        const auto begin = sizes.begin() + std::ptrdiff_t(w);
        const auto end = sizes.begin() + std::ptrdiff_t(std::min(sizes.size(), w + lanes));
        rays += std::accumulate(begin, end, 0LL);
        steps += *std::max_element(begin, end);
    }
    return steps > 0 ? double(rays) / double(steps) : 0.0;
}

LaneEstimate estimateBusyLanes(const Scene& scene, const RenderOptions& options, int warps,
                               WarpShape shape, std::uint64_t seed, int threads) {
    if (warps < 1) throw Error("the warp estimate needs at least one warp");
    const int across = (options.width + shape.width - 1) / shape.width;
    const int down = (options.height + shape.height - 1) / shape.height;
    const long long tiles = (long long)across * down;
    // Distinct warps at random; every warp of a small frame.
    std::vector<long long> picked;
    if (tiles <= warps) {
        picked.resize(std::size_t(tiles));
        std::iota(picked.begin(), picked.end(), 0LL);
    } else {
        std::mt19937_64 rng(seed);
        std::vector<char> taken(std::size_t(tiles), 0);
        while (picked.size() < std::size_t(warps)) {
            const long long t = (long long)(rng() % std::uint64_t(tiles));
            if (!taken[std::size_t(t)]) taken[std::size_t(t)] = 1, picked.push_back(t);
        }
    }
    // Lanes past the frame's edge are work-items without a pixel: no tree.
    std::vector<glm::ivec2> pixels;
    std::vector<int> lane;  // index into pixels, or -1
    for (long long t : picked) {
        const int x0 = int(t % across) * shape.width, y0 = int(t / across) * shape.height;
        for (int dy = 0; dy < shape.height; ++dy)
            for (int dx = 0; dx < shape.width; ++dx) {
                const int x = x0 + dx, y = y0 + dy;
                if (x < options.width && y < options.height) {
                    lane.push_back(int(pixels.size()));
                    pixels.push_back({x, y});
                } else {
                    lane.push_back(-1);
                }
            }
    }
    const std::vector<RayTreeSize> trees = referenceRayTrees(scene, options, pixels, threads);
    std::vector<int> sizes(lane.size()), traced;
    for (std::size_t i = 0; i < lane.size(); ++i)
        sizes[i] = lane[i] < 0 ? 0 : trees[std::size_t(lane[i])].rays;
    for (const RayTreeSize& t : trees) traced.push_back(t.rays);
    long long objects = 0;
    for (std::size_t w = 0; w < lane.size(); w += std::size_t(shape.lanes())) {
        std::vector<long long> seen;
        for (std::size_t i = w; i < w + std::size_t(shape.lanes()); ++i)
            if (lane[i] >= 0) seen.push_back(trees[std::size_t(lane[i])].object);
        std::sort(seen.begin(), seen.end());
        objects += std::unique(seen.begin(), seen.end()) - seen.begin();
    }

    LaneEstimate e;
    e.lanes = shape.lanes();
    e.warps = int(picked.size());
    e.busyLanes = busyLanes(sizes, e.lanes);
    const long long rays = std::accumulate(traced.begin(), traced.end(), 0LL);
    e.raysPerPixel = traced.empty() ? 0.0 : double(rays) / double(traced.size());
    e.largestTree = traced.empty() ? 0 : *std::max_element(traced.begin(), traced.end());
    e.objectsPerWarp = e.warps ? double(objects) / e.warps : 0.0;
    return e;
}

LaneEstimateCache::Key LaneEstimateCache::keyOf(const Scene& scene, const RenderOptions& o) {
    return {scene.id.value(), o.width,      o.height, o.bounces, o.aa,
            o.robustSphere,   o.watertight, o.offset};
}

void LaneEstimateCache::put(const Scene& scene, const RenderOptions& o,
                            const LaneEstimate& estimate, double ms) {
    key_ = keyOf(scene, o);
    estimate_ = estimate;
    ms_ = ms;
    valid_ = true;
}

const LaneEstimate& LaneEstimateCache::get(const Scene& scene, const RenderOptions& o) {
    const Key key = keyOf(scene, o);
    if (!valid_ || !(key_ == key)) {
        const auto start = std::chrono::steady_clock::now();
        estimate_ = estimateBusyLanes(scene, o);
        ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                  .count();
        key_ = key;
        valid_ = true;
    }
    return estimate_;
}

Prediction predictDesign(const LaneEstimate& estimate, double queueBelowLanes) {
    // The threshold is for 32 lanes; a narrower warp scales it.
    const double threshold = queueBelowLanes * estimate.lanes / 32.0;
    char reason[256];
    const bool queue = estimate.busyLanes < threshold;
    std::snprintf(reason, sizeof reason, "%.1f busy lanes of %d a step (%s %.1f): %s",
                  estimate.busyLanes, estimate.lanes, queue ? "below" : "at or above", threshold,
                  queue ? "the trees of neighbouring pixels disagree, compacted queues win"
                        : "neighbouring pixels trace alike trees, one tree a work-item wins");
    return {queue ? "queue" : "tree-per-work-item", reason};
}

}  // namespace rt
