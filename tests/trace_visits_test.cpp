// What one ray costs in each BVH, counted on the host (bench/trace_visits.cpp): the node
// visits, triangle tests and bytes that the trace-peer results name as the bound, checked on rays
// whose work is known from the tree's shape.
#include "bench/trace_visits.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_scenes.h"

namespace rt {
namespace {

Scene triangles(std::initializer_list<dev::Triangle> list) {
    Scene s;
    s.name = "triangles";
    dev::Material m{};
    m.opacity = m.ior = 1.f;
    s.materials = {m};
    s.triangles = list;
    finalizeScene(s);
    return s;
}

dev::Triangle flat(float x0, float y0, float x1, float y1, float x2, float y2, float z) {
    dev::Float3 n{0, 0, 1};
    return {{x0, y0, z}, {x1, y1, z}, {x2, y2, z}, n, n, n, 0, 0};
}

BatchRay down(float x, float y) { return {x, y, 5.f, INFINITY, 0.f, 0.f, -1.f, 0.f}; }

TEST(TraversalCost, ARayMissingTheRootCostsOneRecord) {
    AccelData d = buildAccel(triangles({flat(-1, -1, 1, -1, 0, 1, 0)}), RenderOptions::Accel::Wide);
    std::vector<BatchRay> miss = {{0.f, 0.f, 5.f, INFINITY, 1.f, 0.f, 0.f, 0.f}};
    TraversalCost b = binaryTraversalCost(d, miss, false), w = wideTraversalCost(d, miss, false);
    EXPECT_EQ(b.rays, 1u);
    EXPECT_EQ(b.nodes, 1.0);
    EXPECT_EQ(b.triangles, 0.0);
    EXPECT_EQ(b.bytes, 32.0);  // the root's record
    EXPECT_EQ(w.nodes, 1.0);
    EXPECT_EQ(w.triangles, 0.0);
    EXPECT_EQ(w.bytes, 64.0);
}

TEST(TraversalCost, ARayThroughOneTriangleTestsItOnce) {
    AccelData d = buildAccel(triangles({flat(-1, -1, 1, -1, 0, 1, 0)}), RenderOptions::Accel::Wide);
    std::vector<BatchRay> hit = {down(0.f, 0.f)};
    TraversalCost b = binaryTraversalCost(d, hit, false);
    EXPECT_EQ(b.nodes, 1.0);  // the root is the leaf
    EXPECT_EQ(b.triangles, 1.0);
    EXPECT_EQ(b.bytes, 32.0 + 36.0);
    EXPECT_EQ(wideTraversalCost(d, hit, true).bytes, 64.0 + 36.0);
}

// A small triangle above a large one: a ray through the small one's box, beside the triangle,
// enters both leaves, misses the nearer one and pops the farther one, which loads nothing: its
// (first, count) came in its stack entry.
TEST(TraversalCost, APoppedNodeLoadsNothing) {
    AccelData d =
        buildAccel(triangles({flat(-1, -1, 1, -1, 0, 1, 0), flat(-3, -3, 3, -3, 0, 3, -5)}),
                   RenderOptions::Accel::Wide);
    ASSERT_EQ(d.bvh.size(), 3u);  // a root over two leaves
    std::vector<BatchRay> beside = {down(0.9f, 0.9f)};
    for (bool anyHit : {false, true}) {
        TraversalCost b = binaryTraversalCost(d, beside, anyHit);
        EXPECT_EQ(b.nodes, 3.0) << anyHit;
        EXPECT_EQ(b.triangles, 2.0) << anyHit;
        EXPECT_EQ(b.bytes, 32.0 + 64.0 + 2 * 36.0) << anyHit;  // root, pair, tests
    }
    TraversalCost w = wideTraversalCost(d, beside, false);
    EXPECT_EQ(w.nodes, 1.0);  // one wide node holds both leaves
    EXPECT_EQ(w.triangles, 2.0);
    EXPECT_EQ(w.bytes, 64.0 + 2 * 36.0);
    // Through the small triangle the farther leaf is dropped without being loaded.
    TraversalCost b = binaryTraversalCost(d, {down(0.f, 0.f)}, false);
    EXPECT_EQ(b.nodes, 2.0);
    EXPECT_EQ(b.bytes, 32.0 + 64.0 + 36.0);
}

// The compressed 8-wide BVH: one node holds both leaves; a closest-hit ray beside the small
// triangle tests both (80 B of node, 48 B per leaf entry).
TEST(TraversalCost, CwbvhCountsNodesAndLeafEntries) {
    AccelData d =
        buildAccel(triangles({flat(-1, -1, 1, -1, 0, 1, 0), flat(-3, -3, 3, -3, 0, 3, -5)}),
                   RenderOptions::Accel::Cwbvh);
    ASSERT_EQ(d.cwbvh.size(), 1u);
    TraversalCost c = cwbvhTraversalCost(d, {down(0.9f, 0.9f)}, false);
    EXPECT_EQ(c.nodes, 1.0);
    EXPECT_EQ(c.triangles, 2.0);
    EXPECT_EQ(c.bytes, 80.0 + 2 * 48.0);
    TraversalCost miss =
        cwbvhTraversalCost(d, {{0.f, 0.f, 5.f, INFINITY, 1.f, 0.f, 0.f, 0.f}}, false);
    EXPECT_EQ(miss.nodes, 1.0);
    EXPECT_EQ(miss.triangles, 0.0);
    // 300 random triangles: a node visit tests eight slots, so a ray makes fewer visits than in
    // the binary tree it came from.
    AccelData soup = buildAccel(test::soup(0, 300, 11), RenderOptions::Accel::Cwbvh);
    std::vector<BatchRay> rays;
    for (int i = 0; i < 64; ++i) rays.push_back(down(-20.f + 0.6f * float(i), 3.f));
    c = cwbvhTraversalCost(soup, rays, false);
    TraversalCost b = binaryTraversalCost(soup, rays, false);
    EXPECT_GT(c.nodes, 0.0);
    EXPECT_LT(c.nodes, b.nodes);
}

// A packet of 8 over one triangle: the four rays that come down through it hit, the four that
// run sideways miss the scene. The packet visits the one node once, tests the triangle once
// for all eight, and half its rays are in the leaf that test serves.
TEST(TraversalCost, APacketCountsItsVisitsOnceAndTheRaysEachServes) {
    AccelData d = buildAccel(triangles({flat(-1, -1, 1, -1, 0, 1, 0)}), RenderOptions::Accel::Wide);
    std::vector<BatchRay> rays;
    for (int i = 0; i < 8; ++i)
        rays.push_back(i % 2 ? BatchRay{0.f, 0.f, 5.f, INFINITY, 1.f, 0.f, 0.f, 0.f}
                             : down(0.1f * float(i) - 0.3f, 0.f));
    PacketCost c = widePacketTraversalCost(d, rays, false, 8);
    EXPECT_EQ(c.packets, 1u);
    EXPECT_EQ(c.size, 8);
    EXPECT_EQ(c.nodes, 1.0);
    EXPECT_EQ(c.triangles, 1.0);
    EXPECT_EQ(c.triangleLanes, 0.5);
    EXPECT_EQ(c.nodeLanes, 1.0);  // the root serves every ray
    // Packets of 4 split them into two packets with the same work each.
    PacketCost four = widePacketTraversalCost(d, rays, false, 4);
    EXPECT_EQ(four.packets, 2u);
    EXPECT_EQ(four.triangles, 1.0);
    EXPECT_EQ(four.triangleLanes, 0.5);
    // The single-ray count of the same rays: each ray visits the node, only those through the
    // leaf's box test the triangle.
    TraversalCost single = wideTraversalCost(d, rays, false);
    EXPECT_EQ(single.nodes, 1.0);
    EXPECT_EQ(single.triangles, 0.5);
}

}  // namespace
}  // namespace rt
