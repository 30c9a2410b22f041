// rtlab — the BVH of --accel bvh: one tree over every sphere and triangle, built on
// the host with a binned surface area heuristic (Wald 2007) and flattened for the device
// (core/cl/accel.cl). Subtrees above kParallelTask primitives are built on their own thread and
// the top levels bin in parallel, so the build uses every core; the result does not depend on
// the thread count, because nodes are renumbered depth-first at the end.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

#include "core/accel.h"
#include "core/error.h"

namespace rt {
namespace {

constexpr int kBins = 32;
constexpr int kMaxLeaf = 8;             // SAH may stop splitting at or below this many
constexpr int kMaxDepth = 56;           // device stack is 64 entries; + 1 for a kind split
constexpr int kParallelTask = 16384;    // subtrees at least this large may get their own thread
constexpr int kParallelBin = 262144;    // ranges at least this large bin on every thread
constexpr float kTraversalCost = 1.0f;  // one node visit, in units of one primitive test

struct Box {
    float lo[3] = {INFINITY, INFINITY, INFINITY};
    float hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    void grow(const float* l, const float* h) {
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], l[a]), hi[a] = std::max(hi[a], h[a]);
    }
    void grow(const Box& b) { grow(b.lo, b.hi); }
    void growPoint(const float* p) { grow(p, p); }
    float area() const {
        float d[3];
        for (int a = 0; a < 3; ++a) d[a] = std::max(0.f, hi[a] - lo[a]);
        return 2.f * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
    }
};

struct BuildNode {
    Box box;
    int left = -1;  // first of the two children; -1 for a leaf
    int begin = 0, end = 0;
};

// One primitive during the build: its padded box and id (spheres first, then triangles), kept
// together so that the passes over a range read memory in order.
struct Ref {
    float lo[3];
    int id;
    float hi[3];
    int pad;
    float centroid(int a) const { return 0.5f * (lo[a] + hi[a]); }
};

class Builder {
  public:
    Builder(const PrimBoxes& boxes, unsigned threads)
        : sphereCount_(boxes.sphereCount), threads_(threads) {
        int n = int(boxes.lo.size());
        refs_.resize(n);
        for (int i = 0; i < n; ++i) {
            Ref& r = refs_[i];
            r = {{boxes.lo[i].x, boxes.lo[i].y, boxes.lo[i].z},
                 i,
                 {boxes.hi[i].x, boxes.hi[i].y, boxes.hi[i].z},
                 0};
        }
        nodes_.resize(size_t(std::max(1, 2 * n)));
    }

    void run() {
        next_ = 1;
        busy_ = 1;
        build(0, 0, int(refs_.size()), 0);
        nodes_.resize(size_t(next_.load()));
    }

    const std::vector<BuildNode>& nodes() const { return nodes_; }
    int id(int i) const { return refs_[i].id; }

  private:
    bool isSphere(const Ref& r) const { return r.id < sphereCount_; }

    // Runs fn(chunkBegin, chunkEnd, partial) over [begin, end), on every thread when the range
    // is large, and merges the partial results with merge(into, from).
    template <class T, class Fn, class Merge>
    T reduce(int begin, int end, const T& init, Fn&& fn, Merge&& merge) {
        if (end - begin < kParallelBin || threads_ <= 1) {
            T result = init;
            fn(begin, end, result);
            return result;
        }
        std::vector<T> part(threads_, init);
        std::vector<std::thread> pool;
        int step = int((end - begin + threads_ - 1) / threads_);
        for (unsigned c = 0; c < threads_; ++c)
            pool.emplace_back([&, c] {
                fn(std::min(end, begin + int(c) * step), std::min(end, begin + int(c + 1) * step),
                   part[c]);
            });
        for (std::thread& t : pool) t.join();
        for (unsigned c = 1; c < threads_; ++c) merge(part[0], part[c]);
        return part[0];
    }

    struct Bounds {
        Box box, centroids;
    };

    Bounds bounds(int begin, int end) {
        return reduce<Bounds>(
            begin, end, Bounds{},
            [&](int b, int e, Bounds& out) {
                for (int i = b; i < e; ++i) {
                    const Ref& r = refs_[i];
                    out.box.grow(r.lo, r.hi);
                    float c[3] = {r.centroid(0), r.centroid(1), r.centroid(2)};
                    out.centroids.growPoint(c);
                }
            },
            [](Bounds& into, const Bounds& from) {
                into.box.grow(from.box);
                into.centroids.grow(from.centroids);
            });
    }

    // Bin boxes are initialized only as far as a range uses them (binCount): a Box array of
    // kBins per axis would cost more than the binning itself for the many small ranges.
    struct Bins {
        struct Raw {
            float lo[3], hi[3];
        };
        Raw raw[3][kBins];
        int count[3][kBins];
        Bins() = default;
        explicit Bins(int nb) {
            for (int a = 0; a < 3; ++a)
                for (int k = 0; k < nb; ++k) {
                    count[a][k] = 0;
                    for (int c = 0; c < 3; ++c)
                        raw[a][k].lo[c] = INFINITY, raw[a][k].hi[c] = -INFINITY;
                }
        }
        void grow(int a, int k, const float* lo, const float* hi) {
            Raw& r = raw[a][k];
            for (int c = 0; c < 3; ++c)
                r.lo[c] = std::min(r.lo[c], lo[c]), r.hi[c] = std::max(r.hi[c], hi[c]);
        }
    };

    // Fewer bins for small ranges, where initializing and sweeping them would dominate.
    static int binCount(int count) { return count <= 64 ? 8 : count <= 4096 ? 16 : kBins; }

    static int binOf(const Ref& r, int axis, const Box& cb, float scale, int bins) {
        int b = int((r.centroid(axis) - cb.lo[axis]) * scale);
        return std::clamp(b, 0, bins - 1);
    }

    // Best binned SAH split: axis, first bin of the right side, and its cost (INFINITY if none).
    struct Split {
        int axis = -1, bin = 0;
        float cost = INFINITY;
    };

    Split bestSplit(int begin, int end, const Box& cb, int nb, float* scale) {
        for (int a = 0; a < 3; ++a) {
            float extent = cb.hi[a] - cb.lo[a];
            scale[a] = extent > 0.f ? float(nb) / extent : 0.f;
        }
        Bins bins = reduce<Bins>(
            begin, end, Bins(nb),
            [&](int b, int e, Bins& out) {
                for (int i = b; i < e; ++i) {
                    const Ref& r = refs_[i];
                    for (int a = 0; a < 3; ++a) {
                        if (scale[a] == 0.f) continue;
                        int k = binOf(r, a, cb, scale[a], nb);
                        out.grow(a, k, r.lo, r.hi);
                        ++out.count[a][k];
                    }
                }
            },
            [&](Bins& into, const Bins& from) {
                for (int a = 0; a < 3; ++a)
                    for (int k = 0; k < nb; ++k) {
                        into.grow(a, k, from.raw[a][k].lo, from.raw[a][k].hi);
                        into.count[a][k] += from.count[a][k];
                    }
            });
        Split best;
        for (int a = 0; a < 3; ++a) {
            if (scale[a] == 0.f) continue;
            float rightCost[kBins];
            Box right;
            int n = 0;
            for (int k = nb - 1; k > 0; --k) {
                right.grow(bins.raw[a][k].lo, bins.raw[a][k].hi);
                n += bins.count[a][k];
                rightCost[k] = n ? right.area() * float(n) : 0.f;
            }
            Box left;
            n = 0;
            for (int k = 1; k < nb; ++k) {
                left.grow(bins.raw[a][k - 1].lo, bins.raw[a][k - 1].hi);
                n += bins.count[a][k - 1];
                if (n == 0 || n == end - begin) continue;
                float cost = left.area() * float(n) + rightCost[k];
                if (cost < best.cost) best = {a, k, cost};
            }
        }
        return best;
    }

    void makeLeaf(int node, int begin, int end, const Box& box) {
        BuildNode& n = nodes_[node];
        n.box = box;
        n.begin = begin;
        n.end = end;
        // Leaves hold one kind: a mixed range becomes a node over a sphere leaf and a triangle
        // leaf.
        Ref* mid = std::partition(refs_.data() + begin, refs_.data() + end,
                                  [&](const Ref& r) { return isSphere(r); });
        int m = int(mid - refs_.data());
        if (m == begin || m == end) return;
        int c = next_.fetch_add(2);
        n.left = c;
        for (int k = 0; k < 2; ++k) {
            BuildNode& child = nodes_[c + k];
            child.begin = k ? m : begin;
            child.end = k ? end : m;
            for (int i = child.begin; i < child.end; ++i) child.box.grow(refs_[i].lo, refs_[i].hi);
        }
    }

    void build(int node, int begin, int end, int depth) {
        Bounds b = bounds(begin, end);
        int count = end - begin;
        if (count <= 1 || depth >= kMaxDepth) return makeLeaf(node, begin, end, b.box);
        float scale[3];
        int nb = binCount(count);
        Split split = bestSplit(begin, end, b.centroids, nb, scale);
        float leafCost = float(count);
        float splitCost = kTraversalCost + split.cost / std::max(b.box.area(), 1e-30f);
        int mid;
        if (split.axis >= 0) {
            if (count <= kMaxLeaf && splitCost >= leafCost)
                return makeLeaf(node, begin, end, b.box);
            int a = split.axis;
            const Box& cb = b.centroids;
            Ref* m = std::partition(refs_.data() + begin, refs_.data() + end, [&](const Ref& r) {
                return binOf(r, a, cb, scale[a], nb) < split.bin;
            });
            mid = int(m - refs_.data());
        } else {
            // Every centroid in one point (or one bin): split the range in half.
            if (count <= kMaxLeaf) return makeLeaf(node, begin, end, b.box);
            mid = begin + count / 2;
        }
        BuildNode& n = nodes_[node];
        n.box = b.box;
        n.begin = begin;
        n.end = end;
        int c = next_.fetch_add(2);
        n.left = c;
        bool big = mid - begin >= kParallelTask && end - mid >= kParallelTask;
        bool spawn = big && busy_.fetch_add(1) < int(threads_);
        if (big && !spawn) busy_.fetch_sub(1);
        if (spawn) {
            std::thread left([=, this] { build(c, begin, mid, depth + 1); });
            build(c + 1, mid, end, depth + 1);
            left.join();
            busy_.fetch_sub(1);
        } else {
            build(c, begin, mid, depth + 1);
            build(c + 1, mid, end, depth + 1);
        }
    }

    int sphereCount_;
    unsigned threads_;
    std::vector<Ref> refs_;
    std::vector<BuildNode> nodes_;
    std::atomic<int> next_{1}, busy_{1};
};

dev::Float3 f3(const float* v) { return {v[0], v[1], v[2]}; }

}  // namespace

void buildBvh(AccelData& data, unsigned threads) {
    if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
    data.bvh.clear();
    size_t prims = data.spheres.size() + data.triangles.size();
    if (prims == 0) return;
    if (prims > size_t(1) << 29) throw Error("--accel bvh: too many primitives");
    PrimBoxes boxes = primitiveBoxes(data);
    Builder builder(boxes, threads);
    builder.run();
    const std::vector<BuildNode>& nodes = builder.nodes();

    // Depth-first renumbering with the two children of a node side by side; the leaves take
    // their primitives in this order, so a leaf's spheres or triangles are contiguous.
    std::vector<dev::Sphere> spheres;
    std::vector<dev::Triangle> triangles;
    std::vector<int> sphereSource, triangleSource;
    spheres.reserve(data.spheres.size());
    triangles.reserve(data.triangles.size());
    data.bvh.assign(nodes.size(), dev::BvhNode{});
    int used = 1;
    struct Item {
        int build, out;
    };
    std::vector<Item> stack{{0, 0}};
    while (!stack.empty()) {
        Item it = stack.back();
        stack.pop_back();
        const BuildNode& n = nodes[it.build];
        dev::BvhNode& o = data.bvh[it.out];
        o.lo = f3(n.box.lo);
        o.hi = f3(n.box.hi);
        if (n.left >= 0) {
            o.first = used;
            o.count = 0;
            used += 2;
            stack.push_back({n.left + 1, o.first + 1});
            stack.push_back({n.left, o.first});
            continue;
        }
        bool sphere = builder.id(n.begin) < boxes.sphereCount;
        o.first = int(sphere ? spheres.size() : triangles.size());
        o.count = sphere ? -(n.end - n.begin) : n.end - n.begin;
        for (int i = n.begin; i < n.end; ++i) {
            int p = builder.id(i);
            if (sphere) {
                spheres.push_back(data.spheres[p]);
                sphereSource.push_back(data.sphereSource[p]);
            } else {
                triangles.push_back(data.triangles[p - boxes.sphereCount]);
                triangleSource.push_back(data.triangleSource[p - boxes.sphereCount]);
            }
        }
    }
    data.spheres = std::move(spheres);
    data.triangles = std::move(triangles);
    data.sphereSource = std::move(sphereSource);
    data.triangleSource = std::move(triangleSource);
}

}  // namespace rt
