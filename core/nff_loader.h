// rtlab — Eric Haines' Neutral File Format (NFF, the Standard Procedural Databases' format) into
// rt::Scene; the mapping of viewpoint, materials and lights is docs/NFF.md. Every rejection is one
// line, "<file>: line N: <reason>", thrown as rt::Error.
#pragma once

#include <filesystem>
#include <string>

#include "core/scene.h"

namespace rt {

struct NffOptions {
    // Cones and cylinders (`c`) become this many quads (2 triangles each, one where a radius is
    // 0) around their axis. The default: RTLAB_NFF_CONE_SEGMENTS when set, else 16.
    int coneSegments = 16;
};

// The options a loader gets when nobody asks for others (RTLAB_NFF_CONE_SEGMENTS, 3..1024).
NffOptions defaultNffOptions();

bool isNffFile(const std::filesystem::path& path);  // by extension, .nff in any case

Scene loadNff(const std::filesystem::path& path, const NffOptions& options = defaultNffOptions());

// The same from text in memory; `file` names it in messages and becomes the scene's source.
Scene parseNff(const std::string& text, const std::filesystem::path& file,
               const NffOptions& options = {});

}  // namespace rt
