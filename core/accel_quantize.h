// rtlab — the 8-bit child boxes of the wide BVHs (core/accel_wide.cpp, core/accel_cwbvh.cpp;
// Ylitie, Karras and Laine 2017): a node's box is origin + [0, 255] * step per axis, step a
// power of two 2^(e - 127) that the device decodes from the exponent byte with a shift, and each
// child's bounds are rounded outward so that the decoded box always holds the child's exact one.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/accel.h"
#include "core/types.h"

namespace rt::quant {

// 2^(e - 127), from a float's exponent bits: what the device computes with a shift.
inline float stepOf(uint8_t e) { return std::bit_cast<float>(uint32_t(e) << 23); }

// The smallest exponent whose 255 steps from lo reach hi, in the device's float arithmetic.
inline uint8_t exponentFor(float lo, float hi) {
    int e = 1;  // 0 would be a zero step
    if (hi > lo) {
        int x;
        std::frexp((hi - lo) / 255.f, &x);
        e = std::max(1, x + 125);  // one below the estimate; the loop climbs to the exact one
    }
    while (e < 254 && lo + 255.f * stepOf(uint8_t(e)) < hi) ++e;
    return uint8_t(e);
}

// Outward rounding: the decoded bound origin + q * step never cuts into the child's box.
inline uint8_t quantLo(float origin, float step, float v) {
    int q = std::clamp(int(std::floor((v - origin) / step)), 0, 255);
    while (q > 0 && origin + float(q) * step > v) --q;
    return uint8_t(q);
}
inline uint8_t quantHi(float origin, float step, float v) {
    int q = std::clamp(int(std::ceil((v - origin) / step)), 0, 255);
    while (q < 255 && origin + float(q) * step < v) ++q;
    return uint8_t(q);
}

// An axis-aligned box: a binary node's, a decoded slot's, a primitive's.
struct Box {
    float lo[3], hi[3];
};

inline Box boxOf(const dev::BvhNode& n) {
    return {{n.lo.x, n.lo.y, n.lo.z}, {n.hi.x, n.hi.y, n.hi.z}};
}

// Half the surface area: the collapses open the child of largest area first.
inline float halfArea(const Box& b) {
    float dx = b.hi[0] - b.lo[0], dy = b.hi[1] - b.lo[1], dz = b.hi[2] - b.lo[2];
    return dx * dy + dy * dz + dz * dx;
}

// Slot k's decoded box in a WideNode or CwbvhNode, as the device computes it.
template <typename Node>
Box decode(const Node& n, int k) {
    const uint8_t* qlo[3] = {n.loX, n.loY, n.loZ};
    const uint8_t* qhi[3] = {n.hiX, n.hiY, n.hiZ};
    Box b;
    for (int a = 0; a < 3; ++a) {
        float o = (&n.origin.x)[a], s = stepOf(n.exponent[a]);
        b.lo[a] = o + float(qlo[a][k]) * s;
        b.hi[a] = o + float(qhi[a][k]) * s;
    }
    return b;
}

inline bool contains(const Box& b, const float* lo, const float* hi) {
    for (int a = 0; a < 3; ++a)
        if (lo[a] < b.lo[a] || hi[a] > b.hi[a]) return false;
    return true;
}

inline Box sphereBox(const dev::Sphere& s) {
    const float* c = &s.center.x;
    return {{c[0] - s.radius, c[1] - s.radius, c[2] - s.radius},
            {c[0] + s.radius, c[1] + s.radius, c[2] + s.radius}};
}

inline Box triangleBox(const dev::Triangle& t) {
    Box b;
    for (int a = 0; a < 3; ++a) {
        float v0 = (&t.v0.x)[a], v1 = (&t.v1.x)[a], v2 = (&t.v2.x)[a];
        b.lo[a] = std::min({v0, v1, v2});
        b.hi[a] = std::max({v0, v1, v2});
    }
    return b;
}

// The walk both wide checkers make (checkWide, checkCwbvh): every path from node 0 with the
// decoded boxes above it and the entries the device's stack holds on the way. Each node must be
// reached once, each primitive once, inside every box on its path.
class PathCheck {
  public:
    struct Item {
        int node, pending;  // pending: deferred entries on the device's stack on the way here
        std::vector<Box> path;
    };

    PathCheck(const AccelData& data, size_t nodes, int stackLimit)
        : data_(data),
          nodeSeen_(nodes),
          sphereSeen_(data.spheres.size()),
          triangleSeen_(data.triangles.size()),
          stackLimit_(stackLimit) {}

    // visit(item, where) checks one node and push()es its inner children; it returns "" or the
    // first violation, as run() does.
    template <typename Visit>
    std::string run(Visit visit) {
        stack_.push_back({0, 0, {}});
        while (!stack_.empty()) {
            Item it = std::move(stack_.back());
            stack_.pop_back();
            std::string where = "node " + std::to_string(it.node);
            if (it.node < 0 || size_t(it.node) >= nodeSeen_.size()) return where + " out of range";
            if (nodeSeen_[size_t(it.node)]++) return where + " is reached twice";
            if (it.pending >= stackLimit_) return where + " needs more than the device's stack";
            if (std::string e = visit(it, where); !e.empty()) return e;
        }
        return firstUnvisited(triangleSeen_, sphereSeen_, nodeSeen_);
    }

    void push(Item item) { stack_.push_back(std::move(item)); }

    // Primitive p, a sphere or a triangle, in a leaf below the boxes `path`.
    std::string place(bool sphere, size_t p, const std::vector<Box>& path,
                      const std::string& where) {
        int& seen = sphere ? sphereSeen_[p] : triangleSeen_[p];
        std::string what = (sphere ? "sphere " : "triangle ") + std::to_string(p);
        if (seen++) return what + " is in two leaves";
        Box b = sphere ? sphereBox(data_.spheres[p]) : triangleBox(data_.triangles[p]);
        for (const Box& above : path)
            if (!contains(above, b.lo, b.hi)) return where + ": a box on the path cuts " + what;
        return "";
    }

  private:
    const AccelData& data_;
    std::vector<int> nodeSeen_, sphereSeen_, triangleSeen_;
    std::vector<Item> stack_;
    int stackLimit_;
};

}  // namespace rt::quant
