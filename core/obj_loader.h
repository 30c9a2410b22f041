// rtlab — OBJ meshes through tinyobjloader: n-gons triangulated, missing normals computed
// (area-weighted vertex normals), materials read from the file's .mtl libraries. Errors throw
// rt::Error "<file>: <reason>" (with line when known).
#pragma once

#include <filesystem>
#include <glm/glm.hpp>
#include <string>
#include <vector>

namespace rt {

// The .mtl parameters rtlab's Blinn-Phong material can express (scenes/README.md says how they
// map): colours clamped to [0, 1], Ns to [1, 10000], d to [0, 1], Ni to [1, 4].
struct ObjMaterial {
    std::string name;
    glm::vec3 ambient{0.f}, diffuse{0.8f}, specular{0.f};  // Ka, Kd, Ks
    float shininess = 1.f;                                 // Ns
    float ior = 1.f;                                       // Ni
    float dissolve = 1.f;                                  // d (or 1 - Tr)
    int illum = 2;
};

struct ObjMesh {
    // Three entries per triangle, world units as stored in the file.
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;  // unit length, one per corner
    // From the file's mtllib libraries: materials, and per triangle an index into them (-1: the
    // face has no usemtl, or names a material no library defines).
    std::vector<ObjMaterial> materials;
    std::vector<int> triangleMaterial;
    std::string materialNote;  // why materials are missing ("box.mtl not found"), else empty
};

ObjMesh loadObj(const std::filesystem::path& path);

}  // namespace rt
