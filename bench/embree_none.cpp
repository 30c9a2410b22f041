// rtlab — stands in for bench/embree_peer.cpp when CMake finds no Embree (a GPU host, say), so
// that rtlab-trace-bench still times rtlab's structures; EmbreePeer::available() is false and
// the peer is never constructed.
#include "bench/embree_peer.h"
#include "core/error.h"

namespace rt {

bool EmbreePeer::available() { return false; }

EmbreePeer::EmbreePeer(const Scene&, unsigned) : threads_(0) {
    throw Error("rtlab-trace-bench was built without Embree (scripts/setup installs it)");
}

EmbreePeer::~EmbreePeer() = default;

double EmbreePeer::intersect(const std::vector<BatchRay>&, std::vector<float>&,
                             std::vector<dev::Float3>&) const {
    return 0;
}

double EmbreePeer::occluded(const std::vector<BatchRay>&, std::vector<int>&) const { return 0; }

std::string EmbreePeer::version() const { return "none"; }

}  // namespace rt
