// rtlab — Embree 3 as a peer of rtlab's traversal: the triangles of a scene in one
// Embree scene, and batches of given rays traced through it on every CPU thread. Compiled only
// when CMake finds Embree; without it bench/embree_none.cpp stands in and available() is false.
#pragma once

#include <string>
#include <vector>

#include "core/scene.h"

namespace rt {

// A ray as both peers read it: origin, tMax, direction, unused (the layout of float8 on the
// device, core/cl/trace_rays.cl).
struct BatchRay {
    float ox, oy, oz, tMax;
    float dx, dy, dz, pad;
};

class EmbreePeer {
  public:
    // False when rtlab was built without Embree (bench/embree_none.cpp stands in).
    static bool available();
    EmbreePeer(const Scene& scene, unsigned threads);  // throws rt::Error
    ~EmbreePeer();
    EmbreePeer(const EmbreePeer&) = delete;
    EmbreePeer& operator=(const EmbreePeer&) = delete;

    // Closest hits: t (-1 on a miss) and the geometric normal of the hit. Returns seconds.
    double intersect(const std::vector<BatchRay>& rays, std::vector<float>& t,
                     std::vector<dev::Float3>& normal) const;
    // 1 where the segment from the origin to tMax is blocked. Returns seconds.
    double occluded(const std::vector<BatchRay>& rays, std::vector<int>& blocked) const;

    double buildMs() const { return buildMs_; }
    std::string version() const;

  private:
    void* device_ = nullptr;  // RTCDevice and RTCScene, kept out of this header
    void* scene_ = nullptr;
    unsigned threads_;
    double buildMs_ = 0;
};

}  // namespace rt
