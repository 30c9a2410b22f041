// rtlab — the CPU reference's triangle BVH (private to core/reference.cpp). A brute-force loop
// over 70k bunny triangles is minutes per image; this visits every triangle a brute-force loop
// could accept. Boxes are padded so that rounding in the slab test never culls a triangle that
// the intersection routine would hit; the caller breaks exact ties by triangle index.
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
    explicit Bvh(const std::vector<dev::Triangle>& triangles) {
        const int n = int(triangles.size());
        if (n == 0) return;
        lo_.resize(n), hi_.resize(n), centroid_.resize(n), order_.resize(n);
        for (int i = 0; i < n; ++i) {
            const dev::Triangle& t = triangles[i];
            const glm::dvec3 a(t.v0.x, t.v0.y, t.v0.z), b(t.v1.x, t.v1.y, t.v1.z),
                c(t.v2.x, t.v2.y, t.v2.z);
            lo_[i] = glm::min(a, glm::min(b, c));
            hi_[i] = glm::max(a, glm::max(b, c));
            centroid_[i] = (lo_[i] + hi_[i]) * 0.5;
            order_[i] = i;
        }
        nodes_.reserve(2 * n / kLeafSize + 2);
        build(0, n);
    }

    // Calls visit(triangleIndex) for each triangle whose padded box the ray enters at a t in
    // [0, bound]; visit returns the new bound (a negative bound stops the traversal).
    template <class Visit>
    void traverse(const ref::Ray& ray, Visit&& visit, double bound) const {
        if (nodes_.empty()) return;
        const glm::dvec3 inv = 1.0 / ray.dir;
        int stack[128];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const int index = stack[--top];
            const Node& node = nodes_[index];
            if (!enters(ray, inv, node, bound)) continue;
            if (node.count > 0) {
                for (int i = node.first; i < node.first + node.count; ++i) {
                    bound = visit(order_[i]);
                    if (bound < 0) return;
                }
            } else {
                stack[top++] = node.first;  // right child, after the left one
                stack[top++] = index + 1;
            }
        }
    }

  private:
    static constexpr int kLeafSize = 4;

    struct Node {
        glm::dvec3 lo, hi;
        int first;  // leaf: first entry of order_; inner: right child (the left one follows)
        int count;  // > 0 for leaves
    };

    static bool enters(const ref::Ray& ray, const glm::dvec3& inv, const Node& node, double bound) {
        double t0 = 0, t1 = bound;
        for (int a = 0; a < 3; ++a) {
            if (ray.dir[a] == 0) {
                if (ray.origin[a] < node.lo[a] || ray.origin[a] > node.hi[a]) return false;
                continue;
            }
            double tn = (node.lo[a] - ray.origin[a]) * inv[a];
            double tf = (node.hi[a] - ray.origin[a]) * inv[a];
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
        // Far more than the ~1e-16 relative error of the slab test or the triangle routines.
        const double scale = std::max({1.0, glm::length(lo), glm::length(hi)});
        nodes_[index].lo = lo - 1e-7 * scale;
        nodes_[index].hi = hi + 1e-7 * scale;
        const glm::dvec3 extent = chi - clo;
        int axis = 0;
        if (extent.y > extent[axis]) axis = 1;
        if (extent.z > extent[axis]) axis = 2;
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
