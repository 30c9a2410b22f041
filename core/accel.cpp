// rtlab — acceleration structures: names, the per-scene default, the per-mesh bounding volumes
// (none, bv) and the dispatch to the grid and BVH builders (core/accel_grid.cpp, accel_bvh.cpp).
#include "core/accel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "core/error.h"

namespace rt {

const char* accelName(RenderOptions::Accel accel) {
    switch (accel) {
        case RenderOptions::Accel::None:
            return "none";
        case RenderOptions::Accel::Bv:
            return "bv";
        case RenderOptions::Accel::Grid:
            return "grid";
        case RenderOptions::Accel::Bvh:
            return "bvh";
        case RenderOptions::Accel::Wide:
            return "wide";
        case RenderOptions::Accel::Cwbvh:
            return "cwbvh";
    }
    return "?";
}

RenderOptions::Accel parseAccel(const std::string& name) {
    if (name == "none") return RenderOptions::Accel::None;
    if (name == "bv") return RenderOptions::Accel::Bv;
    if (name == "grid") return RenderOptions::Accel::Grid;
    if (name == "bvh") return RenderOptions::Accel::Bvh;
    if (name == "wide") return RenderOptions::Accel::Wide;
    if (name == "cwbvh") return RenderOptions::Accel::Cwbvh;
    throw Error("--accel " + name + ": must be one of none, bv, grid, bvh, wide, cwbvh");
}

RenderOptions::Accel defaultAccel(const Scene& scene) {
    // Below this many primitives a loop over them costs less than any traversal.
    constexpr size_t kHandful = 64;
    if (scene.spheres.size() + scene.triangles.size() > kHandful) return RenderOptions::Accel::Bvh;
    if (!scene.triangles.empty()) return RenderOptions::Accel::Bv;
    return RenderOptions::Accel::None;
}

namespace {

// The slab normals of dev::Kdop, unnormalized so that dot products round the same way on the
// host and the device: x, y, z and the 4 diagonals.
constexpr double kSlab[RT_SLABS][3] = {{1, 0, 0},  {0, 1, 0},  {0, 0, 1}, {1, 1, 1},
                                       {-1, 1, 1}, {1, -1, 1}, {1, 1, -1}};

// Relative padding of every bounding volume: float slab tests err by a few ulps of the
// coordinates (1e-7 relative); 1e-5 is far above that and far below any primitive's size.
constexpr double kPad = 1e-5;

double maxAbs(const dev::Float3& v) {
    return std::max({std::fabs(double(v.x)), std::fabs(double(v.y)), std::fabs(double(v.z))});
}

void padMeshSpheres(AccelData& data) {
    for (dev::MeshInstance& m : data.meshes) {
        double scale = std::max(1.0, maxAbs(m.sphereCenter) + m.sphereRadius);
        m.sphereRadius = float(m.sphereRadius + kPad * scale);
    }
}

dev::Kdop meshKdop(const AccelData& data, const dev::MeshInstance& m) {
    double lo[RT_SLABS], hi[RT_SLABS];
    std::fill(lo, lo + RT_SLABS, INFINITY);
    std::fill(hi, hi + RT_SLABS, -INFINITY);
    double scale = 1.0;
    for (int t = m.firstTriangle; t < m.firstTriangle + m.triangleCount; ++t) {
        const dev::Triangle& tri = data.triangles[t];
        for (const dev::Float3* v : {&tri.v0, &tri.v1, &tri.v2}) {
            scale = std::max(scale, maxAbs(*v));
            for (int k = 0; k < RT_SLABS; ++k) {
                double d = kSlab[k][0] * v->x + kSlab[k][1] * v->y + kSlab[k][2] * v->z;
                lo[k] = std::min(lo[k], d);
                hi[k] = std::max(hi[k], d);
            }
        }
    }
    dev::Kdop kdop{};
    double pad = 3 * kPad * scale;  // a diagonal's dot product sums three coordinates
    for (int k = 0; k < RT_SLABS; ++k) {
        kdop.lo[k] = m.triangleCount ? float(lo[k] - pad) : 1.f;  // empty: lo > hi, never hit
        kdop.hi[k] = m.triangleCount ? float(hi[k] + pad) : -1.f;
    }
    return kdop;
}

std::string fmt(const char* format, double a, double b = 0, double c = 0) {
    char buf[128];
    std::snprintf(buf, sizeof buf, format, a, b, c);
    return buf;
}

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// CPU time of this process (every thread) since c0.
double cpuMsSince(std::clock_t c0) { return 1e3 * double(std::clock() - c0) / CLOCKS_PER_SEC; }

}  // namespace

PrimBoxes primitiveBoxes(const AccelData& data) {
    PrimBoxes boxes;
    boxes.sphereCount = int(data.spheres.size());
    size_t n = data.spheres.size() + data.triangles.size();
    boxes.lo.resize(n);
    boxes.hi.resize(n);
    double scale = 1.0;
    for (const dev::Sphere& s : data.spheres) scale = std::max(scale, maxAbs(s.center) + s.radius);
    for (const dev::Triangle& t : data.triangles)
        scale = std::max({scale, maxAbs(t.v0), maxAbs(t.v1), maxAbs(t.v2)});
    const float pad = float(kPad * scale);
    boxes.pad = pad;
    size_t i = 0;
    for (const dev::Sphere& s : data.spheres) {
        float r = s.radius + pad;
        boxes.lo[i] = {s.center.x - r, s.center.y - r, s.center.z - r};
        boxes.hi[i] = {s.center.x + r, s.center.y + r, s.center.z + r};
        ++i;
    }
    for (const dev::Triangle& t : data.triangles) {
        boxes.lo[i] = {std::min({t.v0.x, t.v1.x, t.v2.x}) - pad,
                       std::min({t.v0.y, t.v1.y, t.v2.y}) - pad,
                       std::min({t.v0.z, t.v1.z, t.v2.z}) - pad};
        boxes.hi[i] = {std::max({t.v0.x, t.v1.x, t.v2.x}) + pad,
                       std::max({t.v0.y, t.v1.y, t.v2.y}) + pad,
                       std::max({t.v0.z, t.v1.z, t.v2.z}) + pad};
        ++i;
    }
    return boxes;
}

AccelData buildAccel(const Scene& scene, RenderOptions::Accel accel) {
    auto t0 = std::chrono::steady_clock::now();
    std::clock_t c0 = std::clock();  // on a shared machine the wall clock also counts others' work
    AccelData out;
    out.spheres = scene.spheres;
    out.triangles = scene.triangles;
    out.meshes = scene.meshes;
    out.sphereSource.resize(scene.spheres.size());
    out.triangleSource.resize(scene.triangles.size());
    for (size_t i = 0; i < out.sphereSource.size(); ++i) out.sphereSource[i] = int(i);
    for (size_t i = 0; i < out.triangleSource.size(); ++i) out.triangleSource[i] = int(i);
    padMeshSpheres(out);
    AccelStats& s = out.stats;
    s.name = accelName(accel);
    switch (accel) {
        case RenderOptions::Accel::None:
            break;
        case RenderOptions::Accel::Bv:
            for (const dev::MeshInstance& m : out.meshes) out.kdops.push_back(meshKdop(out, m));
            s.nodes = (long long)out.kdops.size();
            s.bytes = out.kdops.size() * sizeof(dev::Kdop);
            s.detail = "7 slab pairs per mesh";
            break;
        case RenderOptions::Accel::Grid: {
            buildGrid(out);
            const dev::Grid& g = out.grid;
            long long cells = (long long)g.nx * g.ny * g.nz;
            size_t prims = out.spheres.size() + out.triangles.size();
            s.nodes = cells;
            s.bytes = out.cells.size() * sizeof(int);
            s.detail = std::to_string(g.nx) + "x" + std::to_string(g.ny) + "x" +
                       std::to_string(g.nz) + " cells, " +
                       fmt("%.2f refs/primitive",
                           prims ? double(out.cells.size() - cells - 1) / double(prims) : 0.0);
            break;
        }
        case RenderOptions::Accel::Bvh: {
            buildBvh(out);
            s.nodes = (long long)out.bvh.size();
            s.bytes = out.bvh.size() * sizeof(dev::BvhNode);
            long long leaves = 0;
            for (const dev::BvhNode& n : out.bvh) leaves += n.count != 0;
            size_t prims = out.spheres.size() + out.triangles.size();
            s.detail = fmt("%.0f leaves, %.2f primitives/leaf, %.0f ms of CPU time", double(leaves),
                           leaves ? double(prims) / double(leaves) : 0.0, cpuMsSince(c0));
            break;
        }
        case RenderOptions::Accel::Wide: {
            buildBvh(out);
            double binaryMs = msSince(t0);
            buildWide(out);
            s.nodes = (long long)out.wide.size();
            s.bytes = out.wide.size() * sizeof(dev::WideNode);
            double slots = 0;
            for (const dev::WideNode& n : out.wide)
                for (int k = 0; k < 4; ++k) slots += n.child[k] != -1;
            s.detail = fmt("%.2f children/node, binned SAH %.1f ms, collapse %.1f ms",
                           out.wide.empty() ? 0.0 : slots / double(out.wide.size()), binaryMs,
                           msSince(t0) - binaryMs) +
                       fmt(", %.0f ms of CPU time", cpuMsSince(c0));
            break;
        }
        case RenderOptions::Accel::Cwbvh: {
            buildBvh(out);
            double binaryMs = msSince(t0);
            buildCwbvh(out);
            s.nodes = (long long)out.cwbvh.size();
            s.bytes = out.cwbvh.size() * sizeof(dev::CwbvhNode) +
                      out.cwbvhPrims.size() * sizeof(dev::CwbvhPrim);
            double slots = 0;
            for (const dev::CwbvhNode& n : out.cwbvh) slots += cwbvhChildren(n);
            s.detail = fmt("%.2f children/node, binned SAH %.1f ms, collapse %.1f ms",
                           out.cwbvh.empty() ? 0.0 : slots / double(out.cwbvh.size()), binaryMs,
                           msSince(t0) - binaryMs) +
                       fmt(", %.0f ms of CPU time", cpuMsSince(c0));
            break;
        }
    }
    s.buildMs = msSince(t0);
    return out;
}

void cropToCenter(Scene& scene, RenderOptions& o, int w, int h) {
    if (w < 1 || h < 1 || w > o.width || h > o.height || (o.width - w) % 2 || (o.height - h) % 2)
        throw Error("crop " + std::to_string(w) + "x" + std::to_string(h) + " of " +
                    std::to_string(o.width) + "x" + std::to_string(o.height) +
                    ": must fit and leave even margins");
    double t = std::tan(0.5 * double(scene.camera.fovY)) * double(h) / double(o.height);
    scene.camera.fovY = float(2.0 * std::atan(t));
    o.width = w;
    o.height = h;
}

std::string firstUnvisited(const std::vector<int>& triangleSeen, const std::vector<int>& sphereSeen,
                           const std::vector<int>& nodeSeen) {
    for (size_t t = 0; t < triangleSeen.size(); ++t)
        if (!triangleSeen[t]) return "triangle " + std::to_string(t) + " is in no leaf";
    for (size_t s = 0; s < sphereSeen.size(); ++s)
        if (!sphereSeen[s]) return "sphere " + std::to_string(s) + " is in no leaf";
    for (size_t i = 0; i < nodeSeen.size(); ++i)
        if (!nodeSeen[i]) return "node " + std::to_string(i) + " is unreachable";
    return "";
}

std::string checkBvh(const AccelData& data) {
    const std::vector<dev::BvhNode>& nodes = data.bvh;
    size_t prims = data.spheres.size() + data.triangles.size();
    if (nodes.empty()) return prims ? "no nodes for " + std::to_string(prims) + " primitives" : "";
    std::vector<int> sphereSeen(data.spheres.size()), triangleSeen(data.triangles.size()),
        nodeSeen(nodes.size());
    auto inside = [](const dev::BvhNode& c, const dev::BvhNode& p) {
        return c.lo.x >= p.lo.x && c.lo.y >= p.lo.y && c.lo.z >= p.lo.z && c.hi.x <= p.hi.x &&
               c.hi.y <= p.hi.y && c.hi.z <= p.hi.z;
    };
    // The unpadded box of a primitive must lie in its leaf's box.
    auto contains = [](const dev::BvhNode& n, const float* lo, const float* hi) {
        return n.lo.x <= lo[0] && n.lo.y <= lo[1] && n.lo.z <= lo[2] && n.hi.x >= hi[0] &&
               n.hi.y >= hi[1] && n.hi.z >= hi[2];
    };
    std::vector<int> stack{0};
    while (!stack.empty()) {
        int i = stack.back();
        stack.pop_back();
        if (i < 0 || size_t(i) >= nodes.size())
            return "node index " + std::to_string(i) + " out of range";
        if (nodeSeen[i]++) return "node " + std::to_string(i) + " is reached twice";
        const dev::BvhNode& n = nodes[i];
        std::string where = "node " + std::to_string(i);
        if (n.count == 0) {
            if (n.first <= 0 || size_t(n.first) + 1 >= nodes.size())
                return where + ": children " + std::to_string(n.first) + " out of range";
            for (int c : {n.first, n.first + 1}) {
                if (!inside(nodes[c], n))
                    return where + ": child " + std::to_string(c) + "'s box is not inside";
                stack.push_back(c);
            }
        } else if (n.count > 0) {
            if (n.first < 0 || size_t(n.first) + n.count > data.triangles.size())
                return where + ": triangle range out of bounds";
            for (int t = n.first; t < n.first + n.count; ++t) {
                if (triangleSeen[t]++) return "triangle " + std::to_string(t) + " is in two leaves";
                const dev::Triangle& tr = data.triangles[t];
                float lo[3], hi[3];
                for (int a = 0; a < 3; ++a) {
                    float v0 = (&tr.v0.x)[a], v1 = (&tr.v1.x)[a], v2 = (&tr.v2.x)[a];
                    lo[a] = std::min({v0, v1, v2});
                    hi[a] = std::max({v0, v1, v2});
                }
                if (!contains(n, lo, hi))
                    return where + ": box does not contain triangle " + std::to_string(t);
            }
        } else {
            if (n.first < 0 || size_t(n.first) - n.count > data.spheres.size())
                return where + ": sphere range out of bounds";
            for (int s = n.first; s < n.first - n.count; ++s) {
                if (sphereSeen[s]++) return "sphere " + std::to_string(s) + " is in two leaves";
                const dev::Sphere& sp = data.spheres[s];
                const float* c = &sp.center.x;
                float lo[3] = {c[0] - sp.radius, c[1] - sp.radius, c[2] - sp.radius};
                float hi[3] = {c[0] + sp.radius, c[1] + sp.radius, c[2] + sp.radius};
                if (!contains(n, lo, hi))
                    return where + ": box does not contain sphere " + std::to_string(s);
            }
        }
    }
    return firstUnvisited(triangleSeen, sphereSeen, nodeSeen);
}

}  // namespace rt
