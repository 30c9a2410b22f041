// rtlab — the warp estimate and the rule of auto/predict.h.
#include "auto/predict.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <random>

#include "auto/handout_order.h"
#include "core/error.h"
#include "core/reference.h"

namespace rt {

namespace {

// Distinct values among `keys`.
int distinct(std::vector<int> keys) {
    std::sort(keys.begin(), keys.end());
    return int(std::unique(keys.begin(), keys.end()) - keys.begin());
}

// `count` distinct values of [0, n) at random with a fixed seed; all of them when n <= count.
std::vector<long long> pick(long long n, int count, std::uint64_t seed) {
    std::vector<long long> picked;
    if (n <= count) {
        picked.resize(std::size_t(n));
        std::iota(picked.begin(), picked.end(), 0LL);
        return picked;
    }
    std::mt19937_64 rng(seed);
    std::vector<char> taken(std::size_t(n), 0);
    while (picked.size() < std::size_t(count)) {
        const long long t = (long long)(rng() % std::uint64_t(n));
        if (!taken[std::size_t(t)]) taken[std::size_t(t)] = 1, picked.push_back(t);
    }
    return picked;
}

// The pixels of the warps `tiles` (16x2 tiles, row by row) into `pixels`, and for each of their
// lanes its index there, or -1 for a lane past the frame's edge: a work-item without a pixel.
void warpPixels(const std::vector<long long>& tiles, WarpShape shape, const RenderOptions& options,
                std::vector<glm::ivec2>& pixels, std::vector<int>& lane) {
    const int across = (options.width + shape.width - 1) / shape.width;
    for (long long t : tiles) {
        const int x0 = int(t % across) * shape.width, y0 = int(t / across) * shape.height;
        for (int dy = 0; dy < shape.height; ++dy)
            for (int dx = 0; dx < shape.width; ++dx) {
                const int x = x0 + dx, y = y0 + dy;
                const bool inside = x < options.width && y < options.height;
                lane.push_back(inside ? int(pixels.size()) : -1);
                if (inside) pixels.push_back({x, y});
            }
    }
}

}  // namespace

glm::ivec2 stripPixel(long long k, int width, int height, int tw, int th) {
    int x = 0, y = 0;
    RT_STRIP_PIXEL(k, width, height, tw, th, x, y);  // handout_order.h, as the kernels take them
    return {x, y};
}

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
    // Distinct warps at random; every warp of a small frame.
    const std::vector<long long> picked = pick((long long)across * down, warps, seed);
    std::vector<glm::ivec2> pixels;
    std::vector<int> lane;  // index into pixels, or -1
    warpPixels(picked, shape, options, pixels, lane);
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

int shadingKey(const Scene& scene, int material) {
    if (material < 0) return kShadeMiss;
    return RT_SHADING_CODE(scene.materials[std::size_t(material)]);  // handout_order.h
}

namespace {

// A mean over warp steps: what they add up to, over how many.
struct Count {
    long long sum = 0, steps = 0;
    void add(long long n, long long s = 1) { sum += n, steps += s; }
    double mean() const { return steps ? double(sum) / double(steps) : 0.0; }
};

// The megakernel's order: step k of a warp runs the k-th ray (depth first) of each lane's tree
// that has one. Adds each step's keys to `keys`, and its lanes with a hit to `shadow` where any;
// returns the warps traced.
int countMegakernelSteps(const Scene& scene, const RenderOptions& options, int warps,
                         std::uint64_t seed, int threads, Count& keys, Count& shadow) {
    const WarpShape shape;
    const int across = (options.width + shape.width - 1) / shape.width;
    const int down = (options.height + shape.height - 1) / shape.height;
    std::vector<glm::ivec2> pixels;
    std::vector<int> lane;
    warpPixels(pick((long long)across * down, warps, seed), shape, options, pixels, lane);
    const auto trees = referenceRayTreeNodes(scene, options, pixels, threads);
    const std::vector<RayTreeNode> none;
    auto treeOf = [&](std::size_t i) -> const std::vector<RayTreeNode>& {
        return lane[i] < 0 ? none : trees[std::size_t(lane[i])];
    };
    for (std::size_t w = 0; w < lane.size(); w += std::size_t(shape.lanes())) {
        std::size_t longest = 0;
        for (std::size_t i = w; i < w + std::size_t(shape.lanes()); ++i)
            longest = std::max(longest, treeOf(i).size());
        for (std::size_t k = 0; k < longest; ++k) {
            std::vector<int> step;
            int hits = 0;
            for (std::size_t i = w; i < w + std::size_t(shape.lanes()); ++i)
                if (k < treeOf(i).size()) {
                    step.push_back(shadingKey(scene, treeOf(i)[k].material));
                    hits += treeOf(i)[k].material >= 0;
                }
            keys.add(distinct(step));
            if (hits) shadow.add(hits);
        }
    }
    return int(lane.size()) / shape.lanes();
}

// The bounce loop's order over one batch's trees: bounce by bounce, 32 consecutive rays of a list
// a step, each ray's children after its list's earlier rays' children. Adds each step's keys as
// traced and as sorted, its lanes with a hit (inline shadow rays), and the list's hits 32 a step
// (a shadow pass).
struct BounceCounts {
    Count traced, sorted, shadowInline, shadowPass;
    void add(const Scene& scene, const std::vector<std::vector<RayTreeNode>>& trees) {
        std::vector<std::pair<std::size_t, int>> list;  // (pixel, node) of one bounce, in order
        for (std::size_t p = 0; p < trees.size(); ++p) list.push_back({p, 0});
        while (!list.empty()) {
            std::vector<int> keys;
            std::vector<char> hit;
            std::vector<std::pair<std::size_t, int>> next;
            for (const auto& [p, n] : list) {
                const RayTreeNode& node = trees[p][std::size_t(n)];
                keys.push_back(shadingKey(scene, node.material));
                hit.push_back(node.material >= 0);
                if (node.reflected >= 0) next.push_back({p, node.reflected});
                if (node.refracted >= 0) next.push_back({p, node.refracted});
            }
            std::vector<int> byKey = keys;
            std::stable_sort(byKey.begin(), byKey.end());
            for (std::size_t w = 0; w < keys.size(); w += 32) {
                const auto begin = std::ptrdiff_t(w);
                const auto end = std::ptrdiff_t(std::min(keys.size(), w + 32));
                traced.add(distinct({keys.begin() + begin, keys.begin() + end}));
                sorted.add(distinct({byKey.begin() + begin, byKey.begin() + end}));
                if (const long long h = std::count(hit.begin() + begin, hit.begin() + end, 1))
                    shadowInline.add(h);
            }
            const long long hits = std::count(hit.begin(), hit.end(), 1);
            shadowPass.add(hits, (hits + 31) / 32);
            list = std::move(next);
        }
    }
};

}  // namespace

ShadingEstimate estimateShadingKeys(const Scene& scene, const RenderOptions& options, int warps,
                                    int batches, int batch, std::uint64_t seed, int threads) {
    if (warps < 1 || batches < 1 || batch < 1)
        throw Error("the shading estimate needs at least one warp and one batch");
    ShadingEstimate e;
    Count keys, shadow;
    e.warps = countMegakernelSteps(scene, options, warps, seed, threads, keys, shadow);
    e.megakernel = keys.mean();
    e.shadowMegakernel = shadow.mean();

    // Batches of consecutive pixels in the persistent megakernel's strip order.
    const long long frame = (long long)options.width * options.height;
    BounceCounts bounce;
    for (long long b : pick((frame + batch - 1) / batch, batches, seed + 1)) {
        std::vector<glm::ivec2> pixels;
        for (long long k = b * batch; k < std::min(frame, (b + 1) * batch); ++k)
            pixels.push_back(stripPixel(k, options.width, options.height));
        bounce.add(scene, referenceRayTreeNodes(scene, options, pixels, threads));
        ++e.batches;
    }
    e.bounce = bounce.traced.mean();
    e.sorted = bounce.sorted.mean();
    e.shadowInline = bounce.shadowInline.mean();
    e.shadowPass = bounce.shadowPass.mean();
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
