// rtlab — the 4-wide BVH of --accel wide: the binary binned-SAH tree of
// core/accel_bvh.cpp collapsed into nodes of up to four children, each child box quantised to
// 8 bits per bound relative to its parent (the node layout of Ylitie, Karras and Laine 2017,
// with the greedy collapse of Wald et al. 2008 instead of their cost-optimal one: the inner
// child of largest area is opened until four children are reached). Traversed by
// core/cl/accel_wide.cl; the primitive order of the binary tree is kept, so leaves are ranges.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/accel.h"
#include "core/accel_quantize.h"
#include "core/error.h"

namespace rt {
namespace {

using namespace quant;

constexpr int kWidth = 4;
constexpr int kStack = 64;  // RT_WIDE_STACK in core/cl/accel_wide.cl

class Collapser {
  public:
    explicit Collapser(const std::vector<dev::BvhNode>& bvh) : bvh_(bvh), height_(bvh.size()) {
        // Children follow their parent in the depth-first numbering: one backward pass.
        for (size_t i = bvh.size(); i-- > 0;)
            if (bvh[i].count == 0)
                height_[i] = 1 + std::max(height_[bvh[i].first], height_[bvh[i].first + 1]);
    }

    std::vector<dev::WideNode> run() {
        out_.push_back({});
        build(0, 0, 0);
        return std::move(out_);
    }

  private:
    // Fills out_[index] from binary node b, `pending` being how many deferred entries the
    // device's stack may hold on the way down to it.
    void build(int index, int b, int pending) {
        const dev::BvhNode& n = bvh_[b];
        std::vector<int> kids;
        if (n.count != 0) {
            kids = {b};  // the whole tree is one leaf
        } else {
            kids = {n.first, n.first + 1};
        }
        // A node defers at most (width - 1) children. Keeping pending + height below the stack
        // size at every node bounds the stack whatever the tree's shape: where the budget runs
        // out the node stays binary, which defers one child per level as the binary tree does.
        int width = std::min(kWidth, 1 + std::max(1, kStack - 1 - pending - height_[b]));
        while (int(kids.size()) < width) {
            int best = -1;
            for (int k = 0; k < int(kids.size()); ++k) {
                const dev::BvhNode& c = bvh_[kids[k]];
                if (c.count == 0 &&
                    (best < 0 || halfArea(boxOf(c)) > halfArea(boxOf(bvh_[kids[best]]))))
                    best = k;
            }
            if (best < 0) break;
            int opened = kids[best];
            kids[best] = bvh_[opened].first;
            kids.push_back(bvh_[opened].first + 1);
        }
        dev::WideNode w{};
        w.origin = n.lo;
        const float* lo = &n.lo.x;
        const float* hi = &n.hi.x;
        float step[3];
        for (int a = 0; a < 3; ++a) {
            w.exponent[a] = exponentFor(lo[a], hi[a]);
            step[a] = stepOf(w.exponent[a]);
        }
        uint8_t* qlo[3] = {w.loX, w.loY, w.loZ};
        uint8_t* qhi[3] = {w.hiX, w.hiY, w.hiZ};
        int childPending = pending + int(kids.size()) - 1;
        std::vector<std::pair<int, int>> inner;  // (slot's node index, binary node)
        for (int k = 0; k < kWidth; ++k) {
            if (k >= int(kids.size())) {
                w.child[k] = -1;
                continue;
            }
            const dev::BvhNode& c = bvh_[kids[k]];
            for (int a = 0; a < 3; ++a) {
                qlo[a][k] = quantLo(lo[a], step[a], (&c.lo.x)[a]);
                qhi[a][k] = quantHi(lo[a], step[a], (&c.hi.x)[a]);
            }
            if (c.count == 0) {
                w.child[k] = int(out_.size());
                out_.push_back({});
                inner.push_back({w.child[k], kids[k]});
                continue;
            }
            int count = std::abs(c.count);
            if (count > 65535)
                throw Error("--accel wide: a leaf of " + std::to_string(count) +
                            " primitives is over the 65535 a wide node can hold");
            w.child[k] = c.first;
            w.count[k] = uint16_t(count);
            if (c.count < 0) w.sphereMask |= uint8_t(1u << k);
        }
        out_[index] = w;
        for (auto [slot, child] : inner) build(slot, child, childPending);
    }

    const std::vector<dev::BvhNode>& bvh_;
    std::vector<int> height_;
    std::vector<dev::WideNode> out_;
};

}  // namespace

void buildWide(AccelData& data) {
    data.wide.clear();
    if (data.bvh.empty()) return;
    data.wide = Collapser(data.bvh).run();
}

std::string checkWide(const AccelData& data) {
    const std::vector<dev::WideNode>& nodes = data.wide;
    size_t prims = data.spheres.size() + data.triangles.size();
    if (nodes.empty()) return prims ? "no nodes for " + std::to_string(prims) + " primitives" : "";
    // A primitive is found only if every decoded box on its path holds it; a node defers all
    // but one of its children on the device's stack.
    PathCheck check(data, nodes.size(), kStack);
    return check.run([&](const PathCheck::Item& it, const std::string& where) -> std::string {
        const dev::WideNode& n = nodes[size_t(it.node)];
        int slots = 0;
        for (int k = 0; k < kWidth; ++k) slots += n.child[k] != -1;
        for (int k = 0; k < kWidth; ++k) {
            if (n.child[k] == -1) continue;
            std::vector<Box> path = it.path;
            path.push_back(decode(n, k));
            if (n.count[k] == 0) {
                check.push({n.child[k], it.pending + slots - 1, std::move(path)});
                continue;
            }
            bool sphere = n.sphereMask >> k & 1;
            size_t end = size_t(n.child[k]) + n.count[k];
            if (n.child[k] < 0 || end > (sphere ? data.spheres.size() : data.triangles.size()))
                return where + ": leaf range out of bounds";
            for (size_t p = size_t(n.child[k]); p < end; ++p)
                if (std::string e = check.place(sphere, p, path, where); !e.empty()) return e;
        }
        return "";
    });
}

}  // namespace rt
