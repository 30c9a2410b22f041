// rtlab — acceleration structures (report 2.2 and 3.6), built on the host and traversed
// by core/cl/accel.cl in both pipelines:
//   none  preliminary checks only: the sphere "behind the ray" test and a bounding sphere per mesh
//   bv    plus a 7-slab bounding volume per mesh (Kay-Kajiya), tested before its triangles
//   grid  uniform grid over every sphere and triangle, 3D-DDA traversal
//   bvh   binned-SAH BVH over every sphere and triangle, built with every core
//   wide  the same BVH collapsed into 4-wide nodes with quantised child boxes
//   cwbvh the same BVH collapsed into compressed 8-wide nodes, children in ray-octant order
//         and each node's leaf primitives side by side (for GPUs)
// Planes are infinite and always tested one by one.
#pragma once

#include <string>
#include <vector>

#include "core/scene.h"

namespace rt {

const char* accelName(RenderOptions::Accel accel);
RenderOptions::Accel parseAccel(const std::string& name);  // throws rt::Error

// The structure a scene gets when neither the command line nor the scene file names one: none
// for a handful of primitives, bv for a few small meshes, bvh for anything larger.
RenderOptions::Accel defaultAccel(const Scene& scene);

struct AccelStats {
    std::string name;     // accelName
    double buildMs = 0;   // host time to build the structure (wall clock)
    long long nodes = 0;  // bvh: nodes; grid: cells; bv: slab volumes; none: 0
    size_t bytes = 0;     // device bytes of the structure (nodes, cells and references)
    std::string detail;   // e.g. "64x32x64 cells, 1.2 refs/primitive" or "depth 24, 4.1 prims/leaf"
};

// Spheres and triangles in the order the device sees them, and the records over them. The bvh
// mode reorders both arrays leaf by leaf; *Source maps each device index to the scene's.
struct AccelData {
    std::vector<dev::Sphere> spheres;
    std::vector<dev::Triangle> triangles;
    std::vector<dev::MeshInstance> meshes;   // bounding spheres padded against rounding
    std::vector<dev::Kdop> kdops;            // bv: one per mesh
    std::vector<dev::BvhNode> bvh;           // bvh, wide: root at 0 (wide: the tree it collapses)
    std::vector<dev::WideNode> wide;         // wide: root at 0, uploaded in place of bvh
    std::vector<dev::CwbvhNode> cwbvh;       // cwbvh: root at 0, uploaded in place of bvh
    std::vector<dev::CwbvhPrim> cwbvhPrims;  // cwbvh: leaf entries, uploaded in place of cells
    dev::Grid grid{};                        // grid: the cell layout of `cells`
    std::vector<int> cells;                  // grid: cell c's refs are cells[cells[c]..cells[c+1])
    std::vector<int> sphereSource, triangleSource;
    AccelStats stats;
};

// A primitive reference in grid cells: a triangle index t >= 0, or a sphere s as ~s (< 0).
inline int sphereRef(int s) { return ~s; }

AccelData buildAccel(const Scene& scene, RenderOptions::Accel accel);

// Builders, one file each (core/accel_bvh.cpp, core/accel_grid.cpp). `threads` = 0 uses every
// core; the result does not depend on it.
void buildBvh(AccelData& data, unsigned threads = 0);
void buildGrid(AccelData& data);
// Collapses data.bvh into data.wide (core/accel_wide.cpp); the primitive order is kept.
void buildWide(AccelData& data);
// Collapses data.bvh into data.cwbvh and data.cwbvhPrims (core/accel_cwbvh.cpp).
void buildCwbvh(AccelData& data);
// The slots of a cwbvh node that hold a child (inner or leaf; the others are empty).
int cwbvhChildren(const dev::CwbvhNode& node);

// Every primitive's box, padded so that float rounding in the slab and DDA tests never culls a
// primitive that its intersection routine would hit. Spheres first, then triangles.
struct PrimBoxes {
    std::vector<dev::Float3> lo, hi;
    int sphereCount = 0;
    float pad = 0;  // how far each box reaches past its primitive
};
PrimBoxes primitiveBoxes(const AccelData& data);

// For benchmarks: turns `options` into a w x h crop from the centre of the frame they describe,
// by narrowing the camera's field of view (SHADING.md section 1: a centred crop of a W x H image
// is the w x h image with tan(fovY'/2) = tan(fovY/2) * h / H). Exact when W - w and H - h are
// even; throws rt::Error otherwise or when the crop is larger than the frame. Brute force
// (--accel none) on a million triangles is timed this way on a frame it can finish.
void cropToCenter(Scene& scene, RenderOptions& options, int w, int h);

// The tail of both checkers: the first triangle or sphere no leaf holds, or node no path
// reaches ("" when every entry was seen).
std::string firstUnvisited(const std::vector<int>& triangleSeen, const std::vector<int>& sphereSeen,
                           const std::vector<int>& nodeSeen);

// Checks the BVH invariants (each primitive in exactly one leaf, each child box inside its
// parent's, one kind per leaf, every node reachable once); returns "" or the first violation.
std::string checkBvh(const AccelData& data);

// Checks the wide BVH: each primitive in exactly one leaf, each decoded child box holding its
// primitives and inside its parent's box, every node reachable once, and no path deeper in
// deferred children than the device's stack; returns "" or the first violation.
std::string checkWide(const AccelData& data);

// Checks the compressed 8-wide BVH: each primitive in exactly one leaf entry (a triangle's with
// its exact vertices), each decoded child box on its path holding it, leaves within their node's
// 32 entries, every node reachable once, and no path needing more than the device's stack;
// returns "" or the first violation.
std::string checkCwbvh(const AccelData& data);

}  // namespace rt
