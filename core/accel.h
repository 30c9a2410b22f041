// rtlab — acceleration structures over a scene's triangles (report 2.2): bounding volumes per
// mesh, a uniform grid, and a BVH. Built on the host, traversed by core/cl/scene.cl.
#pragma once

#include <vector>

#include "core/scene.h"

namespace rt {

const char* accelName(RenderOptions::Accel accel);
RenderOptions::Accel parseAccel(const std::string& name);  // throws rt::Error

// Triangles in the order the device sees them, and the acceleration records over them.
struct AccelData {
    std::vector<dev::Triangle> triangles;
    std::vector<dev::MeshInstance> meshes;
    std::vector<dev::BvhNode> bvh;
};

AccelData buildAccel(const Scene& scene, RenderOptions::Accel accel);

}  // namespace rt
