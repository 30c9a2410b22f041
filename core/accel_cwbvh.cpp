// rtlab — the compressed 8-wide BVH of --accel cwbvh (Ylitie, Karras and Laine 2017),
// for GPUs: the binary binned-SAH tree of core/accel_bvh.cpp collapsed into nodes of up to eight
// children (the inner child of largest area opened first, as in core/accel_wide.cpp), each
// child's box quantised to 8 bits per bound, each child placed in the slot of the node's corner
// it lies towards so that the device visits them roughly nearest first without sorting, and each
// node's leaf primitives copied next to each other (dev::CwbvhPrim). Traversed by
// core/cl/accel_cwbvh.cl.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "core/accel.h"
#include "core/accel_quantize.h"
#include "core/error.h"

namespace rt {
namespace {

using namespace quant;

constexpr int kWidth = 8;
constexpr int kLeafMax = 8;     // meta keeps count - 1 in 3 bits
constexpr int kNodePrims = 32;  // a node's leaf entries fit one 32-bit mask on the device
constexpr int kStack = 64;      // RT_CWBVH_STACK in core/cl/accel_cwbvh.cl

// A child of a node being built: an inner node of the binary tree (bin >= 0), or a run of one
// leaf's primitives. A run of more than kLeafMax (the builder's depth cap can leave such leaves)
// becomes an inner node of its own, whose slots split it.
struct Kid {
    int bin = -1;
    int first = 0, count = 0;
    bool spheres = false;
    bool split = false;  // a run that gets a node of its own
    Box box;
    bool leaf() const { return bin < 0 && !split; }
};

Box merge(const Box& a, const Box& b) {
    Box m;
    for (int k = 0; k < 3; ++k) {
        m.lo[k] = std::min(a.lo[k], b.lo[k]);
        m.hi[k] = std::max(a.hi[k], b.hi[k]);
    }
    return m;
}

class Collapser {
  public:
    Collapser(const AccelData& data, std::vector<dev::CwbvhNode>& nodes,
              std::vector<dev::CwbvhPrim>& prims)
        : data_(data), boxes_(primitiveBoxes(data)), nodes_(nodes), prims_(prims) {}

    void run() {
        nodes_.assign(1, {});
        build(0, expand(kidOf(0)));
    }

  private:
    Kid kidOf(int b) const {
        const dev::BvhNode& n = data_.bvh[b];
        Kid k;
        k.box = boxOf(n);
        if (n.count == 0) {
            k.bin = b;
        } else {
            k.first = n.first;
            k.count = n.count > 0 ? n.count : -n.count;
            k.spheres = n.count < 0;
            k.split = k.count > kLeafMax;
        }
        return k;
    }

    // The run's primitives' padded boxes, as the binary builder bounds them.
    Box runBox(int first, int count, bool spheres) const {
        int base = spheres ? 0 : boxes_.sphereCount;
        Box b{{boxes_.lo[base + first].x, boxes_.lo[base + first].y, boxes_.lo[base + first].z},
              {boxes_.hi[base + first].x, boxes_.hi[base + first].y, boxes_.hi[base + first].z}};
        for (int i = base + first + 1; i < base + first + count; ++i)
            b = merge(b, {{boxes_.lo[i].x, boxes_.lo[i].y, boxes_.lo[i].z},
                          {boxes_.hi[i].x, boxes_.hi[i].y, boxes_.hi[i].z}});
        return b;
    }

    static int leafPrims(const std::vector<Kid>& kids) {
        int n = 0;
        for (const Kid& k : kids) n += k.leaf() ? k.count : 0;
        return n;
    }

    // The children of a node standing for `top`: its two children, opened further, largest area
    // first, while there are fewer than eight and the leaves keep within kNodePrims. A run too
    // long for one slot is cut into slots of kLeafMax, and what does not fit goes on as a run.
    std::vector<Kid> expand(const Kid& top) const {
        std::vector<Kid> kids;
        if (top.bin < 0) {
            int first = top.first, left = top.count;
            while (left > 0) {
                int room = kNodePrims - leafPrims(kids);
                bool lastSlot = int(kids.size()) == kWidth - 1;
                Kid k;
                k.first = first;
                k.spheres = top.spheres;
                if (left <= std::min(kLeafMax, room)) {
                    k.count = left;
                } else if (lastSlot || room < kLeafMax) {
                    k.count = left;
                    k.split = true;
                } else {
                    k.count = kLeafMax;
                }
                k.box = runBox(first, k.count, top.spheres);
                kids.push_back(k);
                first += k.count;
                left -= k.count;
            }
            return kids;
        }
        const dev::BvhNode& n = data_.bvh[top.bin];
        kids = {kidOf(n.first), kidOf(n.first + 1)};
        while (int(kids.size()) < kWidth) {
            int best = -1;
            for (int k = 0; k < int(kids.size()); ++k) {
                if (kids[k].bin < 0) continue;
                const dev::BvhNode& b = data_.bvh[kids[k].bin];
                int added = 0;
                for (int c : {b.first, b.first + 1}) {
                    Kid child = kidOf(c);
                    added += child.leaf() ? child.count : 0;
                }
                if (leafPrims(kids) + added > kNodePrims) continue;
                if (best < 0 || halfArea(kids[k].box) > halfArea(kids[best].box)) best = k;
            }
            if (best < 0) break;
            const dev::BvhNode& b = data_.bvh[kids[best].bin];
            kids[best] = kidOf(b.first);
            kids.push_back(kidOf(b.first + 1));
        }
        return kids;
    }

    // Slot s for each kid: the corner of the node it lies towards. Greedy: the (kid, slot) pair
    // of largest projection of the kid's centre on the corner's direction goes first.
    static std::array<int, kWidth> slotsFor(const std::vector<Kid>& kids, const Box& node) {
        std::array<int, kWidth> slotOf;
        slotOf.fill(-1);
        std::array<bool, kWidth> taken{};
        for (size_t round = 0; round < kids.size(); ++round) {
            float best = 0;
            int bi = -1, bs = -1;
            for (size_t i = 0; i < kids.size(); ++i) {
                if (slotOf[i] >= 0) continue;
                for (int s = 0; s < kWidth; ++s) {
                    if (taken[s]) continue;
                    float score = 0;
                    for (int a = 0; a < 3; ++a) {
                        float d =
                            (kids[i].box.lo[a] + kids[i].box.hi[a]) - (node.lo[a] + node.hi[a]);
                        score += (s >> a & 1) ? d : -d;
                    }
                    if (bi < 0 || score > best) best = score, bi = int(i), bs = s;
                }
            }
            slotOf[bi] = bs;
            taken[bs] = true;
        }
        return slotOf;
    }

    void build(int index, const std::vector<Kid>& kids) {
        Box box = kids[0].box;
        for (const Kid& k : kids) box = merge(box, k.box);
        std::array<int, kWidth> slotOf = slotsFor(kids, box);
        std::array<int, kWidth> kidIn;
        kidIn.fill(-1);
        for (size_t i = 0; i < kids.size(); ++i) kidIn[slotOf[i]] = int(i);

        dev::CwbvhNode n{};
        n.origin = {box.lo[0], box.lo[1], box.lo[2]};
        float step[3];
        for (int a = 0; a < 3; ++a) {
            n.exponent[a] = exponentFor(box.lo[a], box.hi[a]);
            step[a] = stepOf(n.exponent[a]);
        }
        uint8_t* qlo[3] = {n.loX, n.loY, n.loZ};
        uint8_t* qhi[3] = {n.hiX, n.hiY, n.hiZ};
        n.childBase = int(nodes_.size());
        n.primBase = int(prims_.size());
        std::vector<std::pair<int, const Kid*>> inner;  // (node index, kid), in slot order
        int offset = 0;
        for (int s = 0; s < kWidth; ++s) {
            if (kidIn[s] < 0) {
                for (int a = 0; a < 3; ++a) qlo[a][s] = 255, qhi[a][s] = 0;  // no ray enters
                continue;
            }
            const Kid& k = kids[kidIn[s]];
            for (int a = 0; a < 3; ++a) {
                qlo[a][s] = quantLo(box.lo[a], step[a], k.box.lo[a]);
                qhi[a][s] = quantHi(box.lo[a], step[a], k.box.hi[a]);
            }
            if (!k.leaf()) {
                n.innerMask |= uint8_t(1u << s);
                inner.push_back({n.childBase + int(inner.size()), &k});
                continue;
            }
            n.meta[s] = uint8_t(offset | (k.count - 1) << 5);
            for (int i = k.first; i < k.first + k.count; ++i)
                prims_.push_back(primOf(i, k.spheres));
            offset += k.count;
        }
        nodes_[index] = n;
        nodes_.resize(nodes_.size() + inner.size());
        for (auto [child, kid] : inner) build(child, expand(*kid));
    }

    dev::CwbvhPrim primOf(int i, bool sphere) const {
        dev::CwbvhPrim p{};
        if (sphere) {
            p.ref = sphereRef(i);
            return p;
        }
        const dev::Triangle& t = data_.triangles[i];
        p.v0 = t.v0;
        p.v1 = t.v1;
        p.v2 = t.v2;
        p.ref = i;
        return p;
    }

    const AccelData& data_;
    PrimBoxes boxes_;
    std::vector<dev::CwbvhNode>& nodes_;
    std::vector<dev::CwbvhPrim>& prims_;
};

bool sameVertices(const dev::Triangle& t, const dev::CwbvhPrim& p) {
    auto same = [](const dev::Float3& a, const dev::Float3& b) {
        return a.x == b.x && a.y == b.y && a.z == b.z;
    };
    return same(t.v0, p.v0) && same(t.v1, p.v1) && same(t.v2, p.v2);
}

bool emptySlot(const dev::CwbvhNode& n, int k) {
    return n.loX[k] == 255 && n.loY[k] == 255 && n.loZ[k] == 255 && n.hiX[k] == 0 &&
           n.hiY[k] == 0 && n.hiZ[k] == 0;
}

}  // namespace

int cwbvhChildren(const dev::CwbvhNode& node) {
    int n = 0;
    for (int k = 0; k < kWidth; ++k) n += (node.innerMask >> k & 1) || !emptySlot(node, k);
    return n;
}

void buildCwbvh(AccelData& data) {
    data.cwbvh.clear();
    data.cwbvhPrims.clear();
    if (data.bvh.empty()) return;
    Collapser(data, data.cwbvh, data.cwbvhPrims).run();
}

std::string checkCwbvh(const AccelData& data) {
    const std::vector<dev::CwbvhNode>& nodes = data.cwbvh;
    size_t prims = data.spheres.size() + data.triangles.size();
    if (nodes.empty()) return prims ? "no nodes for " + std::to_string(prims) + " primitives" : "";
    if (data.cwbvhPrims.size() != prims)
        return std::to_string(data.cwbvhPrims.size()) + " leaf entries for " +
               std::to_string(prims) + " primitives";
    // Every decoded box on a primitive's path must hold it. Descending into an inner child, the
    // device stacks the node's other inner children as one group.
    PathCheck check(data, nodes.size(), kStack);
    return check.run([&](const PathCheck::Item& it, const std::string& where) -> std::string {
        const dev::CwbvhNode& n = nodes[size_t(it.node)];
        int pending = it.pending + (std::popcount(unsigned(n.innerMask)) > 1 ? 1 : 0);
        int rank = 0;
        uint32_t used = 0;  // the node's leaf entries, as the device's mask
        for (int k = 0; k < kWidth; ++k) {
            bool inner = n.innerMask >> k & 1;
            if (!inner && emptySlot(n, k)) continue;
            std::vector<Box> path = it.path;
            path.push_back(decode(n, k));
            if (inner) {
                check.push({n.childBase + rank++, pending, std::move(path)});
                continue;
            }
            int offset = n.meta[k] & 31, count = (n.meta[k] >> 5) + 1;
            if (offset + count > kNodePrims) return where + ": a leaf past the node's 32 entries";
            uint32_t bits = uint32_t((uint64_t(1) << count) - 1) << offset;
            if (used & bits) return where + ": two leaves share an entry";
            used |= bits;
            size_t end = size_t(n.primBase) + size_t(offset + count);
            if (n.primBase < 0 || end > data.cwbvhPrims.size())
                return where + ": leaf entries out of bounds";
            for (size_t e = size_t(n.primBase) + size_t(offset); e < end; ++e) {
                const dev::CwbvhPrim& p = data.cwbvhPrims[e];
                bool sphere = p.ref < 0;
                int i = sphere ? sphereRef(p.ref) : p.ref;
                if (size_t(i) >= (sphere ? data.spheres.size() : data.triangles.size()))
                    return where + ": entry " + std::to_string(e) + " names no primitive";
                if (!sphere && !sameVertices(data.triangles[size_t(i)], p))
                    return where + ": entry " + std::to_string(e) + " is not triangle " +
                           std::to_string(i) + "'s vertices";
                if (std::string err = check.place(sphere, size_t(i), path, where); !err.empty())
                    return err;
            }
        }
        return "";
    });
}

}  // namespace rt
