// rtlab — glTF 2.0 (.gltf, .glb) and PLY models through assimp: every mesh of the node hierarchy
// placed in world space, triangles only (points and lines are dropped), missing or unusable
// normals computed, materials mapped onto rtlab's Blinn-Phong material (scenes/README.md, "glTF
// and PLY models"), the file's first perspective camera and its point lights. Errors throw
// rt::Error "<file>: <reason>" on one line.
#pragma once

#include <chrono>
#include <filesystem>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/types.h"

namespace rt {

// The material a model's faces get when the file gives them none (PLY without vertex colours,
// bare OBJ faces without usemtl): grey diffuse 0.7, specular 0.2, exponent 32, ambient 0.05.
dev::Material defaultModelMaterial();

// A camera the file defines, in world space.
struct ModelCamera {
    glm::vec3 position{0.f};
    glm::vec3 direction{0.f, 0.f, 1.f};  // unit length
    float fovY = 0.f;                    // vertical field of view, radians, in (0, pi)
};

struct Model {
    // Three entries per triangle, world space (the node transforms applied).
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;     // unit length, one per corner
    std::vector<int> triangleMaterial;  // per triangle, an index into materials
    std::vector<dev::Material> materials;
    std::vector<std::string> materialNames;  // parallel to materials
    std::optional<ModelCamera> camera;       // the first perspective camera, if any
    std::vector<dev::Light> lights;          // point and spot lights, at most RT_MAX_LIGHTS
    // What was read differently from the file ("textures are not supported"); never an error.
    std::vector<std::string> notes;
};

// True for the extensions loadModel reads: .gltf, .glb, .ply (any case).
bool isModelFile(const std::filesystem::path& path);

// Reads the file. assimp runs in a child process (core/model_loader.cpp says why): a file on which
// it crashes, or that it does not finish reading within the time limit, fails with one line.
Model loadModel(const std::filesystem::path& path);

// The time limit of loadModel's reader process, 120 s unless set; the fuzz targets shorten it
// below libFuzzer's limit per input.
void setModelReadTimeLimit(std::chrono::milliseconds limit);

}  // namespace rt
