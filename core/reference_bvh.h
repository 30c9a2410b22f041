// rtlab — the CPU reference's BVHs over triangles and spheres (private to core/reference.cpp). A
// brute-force loop over 70k bunny triangles or 100k spheres is minutes per image; a traversal
// visits every primitive a brute-force loop could accept. Boxes are padded so that rounding in
// the slab test and in the intersection routines never culls a primitive that the routine would
// hit at a t within the bound; the caller breaks exact ties in the brute-force order, so the
// closest hit does not depend on the order in which the traversal offers primitives.
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>
#include <vector>

#include "core/reference.h"
#include "core/types.h"

namespace rt::refbvh {

class Bvh {
  public:
    Bvh() = default;

    static Bvh overTriangles(const std::vector<dev::Triangle>& triangles) {
        std::vector<glm::dvec3> lo(triangles.size()), hi(triangles.size());
        for (std::size_t i = 0; i < triangles.size(); ++i) {
            const dev::Triangle& t = triangles[i];
            const glm::dvec3 a(t.v0.x, t.v0.y, t.v0.z), b(t.v1.x, t.v1.y, t.v1.z),
                c(t.v2.x, t.v2.y, t.v2.z);
            lo[i] = glm::min(a, glm::min(b, c));
            hi[i] = glm::max(a, glm::max(b, c));
        }
        return Bvh(std::move(lo), std::move(hi));
    }

    static Bvh overSpheres(const std::vector<dev::Sphere>& spheres) {
        std::vector<glm::dvec3> lo(spheres.size()), hi(spheres.size());
        for (std::size_t i = 0; i < spheres.size(); ++i) {
            const dev::Sphere& s = spheres[i];
            const glm::dvec3 c(s.center.x, s.center.y, s.center.z);
            const double r = std::abs(double(s.radius));
            lo[i] = c - r, hi[i] = c + r;
        }
        return Bvh(std::move(lo), std::move(hi));
    }

    bool empty() const { return nodes_.empty(); }

    // Calls visit(index) for each primitive whose padded box the ray enters at a t in
    // [0, bound]; visit returns the new bound (a negative bound stops the traversal). Children
    // are visited near side first along their split axis, so that a closest-hit query tightens
    // its bound early; the set of primitives visited never depends on that order's result.
    template <class Visit>
    void traverse(const ref::Ray& ray, Visit&& visit, double bound) const {
        if (nodes_.empty()) return;
        const glm::dvec3 inv = 1.0 / ray.dir;
        // The sphere routines' t is off by up to a few 1e-8 of the origin's distance to the
        // centre (the square root of the discriminant's rounding, at grazing angles), which a
        // box padded by its own coordinates alone does not cover when the origin is far away.
        const double pad = kPad * std::max({std::abs(ray.origin.x), std::abs(ray.origin.y),
                                            std::abs(ray.origin.z)});
        int stack[128];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const int index = stack[--top];
            const Node& node = nodes_[index];
            if (!enters(ray, inv, node, pad, bound)) continue;
            if (node.count > 0) {
                for (int i = node.first; i < node.first + node.count; ++i) {
                    bound = visit(order_[i]);
                    if (bound < 0) return;
                }
            } else if (ray.dir[node.axis] < 0) {
                stack[top++] = index + 1;  // the left child, after the right one
                stack[top++] = node.first;
            } else {
                stack[top++] = node.first;  // the right child, after the left one
                stack[top++] = index + 1;
            }
        }
    }

  private:
    static constexpr int kLeafSize = 4;
    // Relative padding of the boxes (by their coordinates) and of the ray (by its origin's):
    // far more than the ~1e-16 relative error of the slab test or the triangle routines, and
    // 20 times the ~5e-8 of the plain sphere routine's t at grazing angles.
    static constexpr double kPad = 1e-6;

    struct Node {
        glm::dvec3 lo, hi;
        int first;  // leaf: first entry of order_; inner: right child (the left one follows)
        int count;  // > 0 for leaves
        int axis;   // inner: the axis the children were split on
    };

    Bvh(std::vector<glm::dvec3> lo, std::vector<glm::dvec3> hi)
        : lo_(std::move(lo)), hi_(std::move(hi)) {
        const int n = int(lo_.size());
        if (n == 0) return;
        centroid_.resize(n), order_.resize(n);
        for (int i = 0; i < n; ++i) {
            centroid_[i] = (lo_[i] + hi_[i]) * 0.5;
            order_[i] = i;
        }
        nodes_.reserve(2 * n / kLeafSize + 2);
        build(0, n);
        // Only the nodes and the order are needed to traverse.
        lo_ = {}, hi_ = {}, centroid_ = {};
    }

    static bool enters(const ref::Ray& ray, const glm::dvec3& inv, const Node& node, double pad,
                       double bound) {
        double t0 = 0, t1 = bound;
        for (int a = 0; a < 3; ++a) {
            const double lo = node.lo[a] - pad, hi = node.hi[a] + pad;
            if (ray.dir[a] == 0) {
                if (ray.origin[a] < lo || ray.origin[a] > hi) return false;
                continue;
            }
            double tn = (lo - ray.origin[a]) * inv[a];
            double tf = (hi - ray.origin[a]) * inv[a];
            if (tn > tf) std::swap(tn, tf);
            t0 = std::max(t0, tn), t1 = std::min(t1, tf);
            if (t0 > t1) return false;
        }
        return true;
    }

    int build(int begin, int end) {
        const int index = int(nodes_.size());
        nodes_.push_back({});
        glm::dvec3 lo(INFINITY), hi(-INFINITY), clo(INFINITY), chi(-INFINITY);
        for (int i = begin; i < end; ++i) {
            lo = glm::min(lo, lo_[order_[i]]), hi = glm::max(hi, hi_[order_[i]]);
            clo = glm::min(clo, centroid_[order_[i]]), chi = glm::max(chi, centroid_[order_[i]]);
        }
        const double scale = std::max({1.0, glm::length(lo), glm::length(hi)});
        nodes_[index].lo = lo - kPad * scale;
        nodes_[index].hi = hi + kPad * scale;
        const glm::dvec3 extent = chi - clo;
        int axis = 0;
        if (extent.y > extent[axis]) axis = 1;
        if (extent.z > extent[axis]) axis = 2;
        nodes_[index].axis = axis;
        if (end - begin <= kLeafSize || extent[axis] <= 0) {
            nodes_[index].first = begin, nodes_[index].count = end - begin;
            return index;
        }
        const int mid = (begin + end) / 2;
        std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                         [&](int a, int b) { return centroid_[a][axis] < centroid_[b][axis]; });
        build(begin, mid);  // lands at index + 1
        const int right = build(mid, end);
        nodes_[index].first = right;
        nodes_[index].count = 0;
        return index;
    }

    std::vector<Node> nodes_;
    std::vector<int> order_;
    std::vector<glm::dvec3> lo_, hi_, centroid_;
};

}  // namespace rt::refbvh
