// rtlab — the work one ray does in the binary and the wide BVHs, counted on the host:
// node visits, triangles tested and bytes fetched per ray, in the traversal order of
// core/cl/accel.cl (Bvh_Query), core/cl/accel_wide.cl and core/cl/accel_cwbvh.cl; and per packet of
// rays in that of core/cl/accel_wide_packet.cl, with the share of its rays each node and triangle
// serves. rtlab-trace-bench prints it beside the rays/s, so that a missed figure names its bound.
#pragma once

#include <vector>

#include "bench/embree_peer.h"
#include "core/accel.h"

namespace rt {

struct TraversalCost {
    double nodes = 0;      // nodes visited per ray
    double triangles = 0;  // triangle tests per ray
    double bytes = 0;  // node records and triangle vertices (36 B) read per ray (wide: 64 B a node)
    size_t rays = 0;   // how many rays were followed (an even sample of the batch)
};

// Binary BVH: nodes are inner and leaf visits; bytes count the root record (32 B), each inner
// node's pair of child records (64 B) and the triangles' vertices (36 B). A deferred node costs
// no load when popped: its (first, count) travels in its stack entry (core/cl/accel.cl).
TraversalCost binaryTraversalCost(const AccelData& bvh, const std::vector<BatchRay>& rays,
                                  bool anyHit, size_t maxRays = 65536);

TraversalCost wideTraversalCost(const AccelData& wide, const std::vector<BatchRay>& rays,
                                bool anyHit, size_t maxRays = 65536);

// Compressed 8-wide BVH (core/cl/accel_cwbvh.cl): nodes are node visits (80 B each), triangles
// the leaf entries tested (48 B each); deferred groups are not culled by distance, so `nodes`
// counts the visits that find nothing left to enter as well.
TraversalCost cwbvhTraversalCost(const AccelData& cwbvh, const std::vector<BatchRay>& rays,
                                 bool anyHit, size_t maxRays = 65536);

// The packet traversal of core/cl/accel_wide_packet.cl (Wide_QueryPacket), `packet` consecutive
// rays at a time: what a packet does, and how many of its rays each step serves.
struct PacketCost {
    double nodes = 0;          // nodes visited per packet
    double triangles = 0;      // triangles tested per packet (each against every ray of it)
    double nodeLanes = 0;      // of a visited node: the share of the packet's rays that enter it
                               // before their current hit (the rest of the lanes ride along)
    double triangleLanes = 0;  // of a tested triangle: the share of rays that enter its leaf
    size_t packets = 0;        // how many packets were followed (an even sample of the batch)
    int size = 0;              // rays per packet
};

PacketCost widePacketTraversalCost(const AccelData& wide, const std::vector<BatchRay>& rays,
                                   bool anyHit, int packet, size_t maxRays = 65536);

}  // namespace rt
