// rtlab — scene files (JSON, documented in scenes/README.md; NFF, core/nff_loader.h) and bare OBJ,
// glTF and PLY models.
// Every validation failure throws rt::Error with one line: "<file>: <json-pointer>: <reason>",
// e.g. "scenes/bad.json: /spheres/2/radius: must be > 0, got -1".
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "core/image.h"
#include "core/scene.h"

namespace rt {

// Reads an image file (cubemap faces). Injected so that rtlab_core does not link OpenImageIO;
// rtlab_image provides readImage(). Without a reader, a scene with a cubemap is an error.
using ImageReader = std::function<Image(const std::filesystem::path&)>;

// Loads a .json or .nff scene, or wraps a bare .obj, .gltf, .glb or .ply model in the default scene
// (camera framing its bounds, one light, a ground plane; a glTF's own camera and lights where it
// has them). Relative paths inside a scene resolve against the scene's directory.
Scene loadScene(const std::filesystem::path& path, const ImageReader& readImage = {});

// A scene file's whole text (at most 256 MiB); a folder, an unreadable or a larger file throws
// one line naming it (the JSON and NFF readers share it).
std::string readTextFile(const std::filesystem::path& path);

// Fills mesh bounds (box and sphere) and checks limits; the loader calls it, tests may too.
void finalizeScene(Scene& scene);

}  // namespace rt
