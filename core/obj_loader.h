// rtlab — OBJ meshes through tinyobjloader: n-gons triangulated, missing normals computed
// (area-weighted vertex normals). Errors throw rt::Error "<file>: <reason>" (with line when known).
#pragma once

#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

namespace rt {

struct ObjMesh {
    // Three entries per triangle, world units as stored in the file.
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;  // unit length, one per corner
};

ObjMesh loadObj(const std::filesystem::path& path);

}  // namespace rt
