// rtlab — the uniform grid of --accel grid: every sphere and triangle is listed in each
// cell its padded box overlaps (triangles only where their plane crosses the cell), and
// core/cl/accel.cl walks the cells along the ray by 3D-DDA (Amanatides and Woo 1987; Xiao et
// al. 2012). The resolution follows the primitive count: about kDensity cells per primitive,
// shaped like the scene's bounding box (Cleary and Wyvill 1988).
#include <algorithm>
#include <cmath>

#include "core/accel.h"
#include "core/error.h"

namespace rt {
namespace {

constexpr double kDensity = 4.0;       // cells per primitive
constexpr int kMaxResolution = 1024;   // per axis
constexpr double kMaxCells = 1 << 24;  // 64 MiB of cell offsets
constexpr double kMaxRefs = 1 << 28;   // 1 GiB of references: refuse rather than thrash

struct CellRange {
    int lo[3], hi[3];
};

}  // namespace

void buildGrid(AccelData& data) {
    PrimBoxes boxes = primitiveBoxes(data);
    const int n = int(boxes.lo.size());
    data.grid = dev::Grid{};
    data.cells.assign(1, 0);
    if (n == 0) return;

    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < n; ++i) {
        const float* l = &boxes.lo[i].x;
        const float* h = &boxes.hi[i].x;
        for (int a = 0; a < 3; ++a)
            lo[a] = std::min(lo[a], double(l[a])), hi[a] = std::max(hi[a], double(h[a]));
    }
    double extent[3], maxExtent = 0;
    for (int a = 0; a < 3; ++a) maxExtent = std::max(maxExtent, hi[a] - lo[a]);
    for (int a = 0; a < 3; ++a) extent[a] = std::max(hi[a] - lo[a], 1e-3 * maxExtent);
    // Cells of edge s with extent^3 / s^3 = kDensity * n: cubes, as many as the count asks.
    double s = std::cbrt(extent[0] * extent[1] * extent[2] / (kDensity * n));
    int res[3];
    for (;;) {
        for (int a = 0; a < 3; ++a)
            res[a] = std::clamp(int(std::ceil(extent[a] / s)), 1, kMaxResolution);
        if (double(res[0]) * res[1] * res[2] <= kMaxCells) break;
        s *= 1.1;
    }
    dev::Grid& g = data.grid;
    g.lo = {float(lo[0]), float(lo[1]), float(lo[2])};
    g.hi = {float(hi[0]), float(hi[1]), float(hi[2])};
    g.nx = res[0], g.ny = res[1], g.nz = res[2];
    float cell[3], inv[3];
    for (int a = 0; a < 3; ++a) {
        cell[a] = float((hi[a] - lo[a]) / res[a]);
        inv[a] = cell[a] > 0.f ? 1.f / cell[a] : 0.f;
    }
    g.cellSize = {cell[0], cell[1], cell[2]};
    g.invCellSize = {inv[0], inv[1], inv[2]};
    const float* glo = &g.lo.x;

    // The device finds a point's cell as floor((p - lo) * invCellSize); the same formula on the
    // padded boxes lists each primitive in every cell a ray could find it in.
    auto range = [&](int i) {
        CellRange r;
        const float* l = &boxes.lo[i].x;
        const float* h = &boxes.hi[i].x;
        for (int a = 0; a < 3; ++a) {
            r.lo[a] = std::clamp(int(std::floor((l[a] - glo[a]) * inv[a])), 0, res[a] - 1);
            r.hi[a] = std::clamp(int(std::floor((h[a] - glo[a]) * inv[a])), 0, res[a] - 1);
        }
        return r;
    };
    // Triangles skip the cells of their box that their plane misses, with the box padding as
    // margin (a large diagonal triangle would otherwise fill a whole slab of cells).
    auto crosses = [&](int i, int x, int y, int z) {
        if (i < boxes.sphereCount) return true;
        const dev::Triangle& t = data.triangles[i - boxes.sphereCount];
        double e1[3] = {t.v1.x - double(t.v0.x), t.v1.y - double(t.v0.y), t.v1.z - double(t.v0.z)};
        double e2[3] = {t.v2.x - double(t.v0.x), t.v2.y - double(t.v0.y), t.v2.z - double(t.v0.z)};
        double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
        int c[3] = {x, y, z};
        double dist = 0, reach = 0, len = 0;
        for (int a = 0; a < 3; ++a) {
            double half = 0.5 * cell[a];
            double center = glo[a] + (c[a] + 0.5) * double(cell[a]);
            dist += nrm[a] * (center - (&t.v0.x)[a]);
            reach += std::fabs(nrm[a]) * half;
            len += nrm[a] * nrm[a];
        }
        return std::fabs(dist) <= reach + 2.0 * boxes.pad * std::sqrt(len);
    };
    auto cellIndex = [&](int x, int y, int z) { return (size_t(z) * res[1] + y) * res[0] + x; };

    const size_t cells = size_t(res[0]) * res[1] * res[2];
    std::vector<int> count(cells + 1, 0);
    double refs = 0;
    for (int i = 0; i < n; ++i) {
        CellRange r = range(i);
        for (int z = r.lo[2]; z <= r.hi[2]; ++z)
            for (int y = r.lo[1]; y <= r.hi[1]; ++y)
                for (int x = r.lo[0]; x <= r.hi[0]; ++x)
                    if (crosses(i, x, y, z)) ++count[cellIndex(x, y, z)], ++refs;
        if (refs > kMaxRefs) throw Error("--accel grid: more than 2^28 cell references; use bvh");
    }
    // Offsets are absolute indices into data.cells: the cell table comes first, then the refs.
    data.cells.resize(cells + 1 + size_t(refs));
    size_t offset = cells + 1;
    for (size_t c = 0; c < cells; ++c) {
        data.cells[c] = int(offset);
        offset += size_t(count[c]);
        count[c] = data.cells[c];  // reused as the fill position
    }
    data.cells[cells] = int(offset);
    // Spheres, then triangles, each in index order: a cell tests them in the brute-force order.
    for (int i = 0; i < n; ++i) {
        int ref = i < boxes.sphereCount ? sphereRef(i) : i - boxes.sphereCount;
        CellRange r = range(i);
        for (int z = r.lo[2]; z <= r.hi[2]; ++z)
            for (int y = r.lo[1]; y <= r.hi[1]; ++y)
                for (int x = r.lo[0]; x <= r.hi[0]; ++x)
                    if (crosses(i, x, y, z)) data.cells[size_t(count[cellIndex(x, y, z)]++)] = ref;
    }
}

}  // namespace rt
