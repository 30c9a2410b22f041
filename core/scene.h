// rtlab — the host-side scene: flat arrays of the device records from types.h, plus what only
// the host needs (names, the environment's cubemap texels, default render settings).
// Built by the loader (core/scene_loader.h), consumed unchanged by every pipeline.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/pipeline_options.h"
#include "core/types.h"

namespace rt {

// Settings a scene file may default and the command line may override.
struct RenderOptions {
    int width = 320, height = 240;
    int bounces = 3;          // B
    int shadowSamples = 1;    // per light with radius > 0 (hard shadows use 1)
    int aa = 1;               // N: N x N sub-pixel samples
    bool adaptiveAa = false;  // supersample only pixels on edges (report section 2.1.2)
    float shadowStrength = 1.0f;

    // Accuracy switches. Defaults are the robust methods.
    bool robustSphere = true;  // false: report Algorithm 2 (plain quadratic)
    bool watertight = true;    // false: report Algorithm 3 (Moller-Trumbore)
    // Secondary-ray origins (core/SHADING.md section 3): a fixed 1e-4, 1e-4 max(1, |p|), or a
    // bound on the hit point's rounding error (the default).
    enum class Offset { Fixed, Scaled, Bound };
    Offset offset = Offset::Bound;

    // Pipeline choices; the CPU reference ignores them.
    size_t memoryBudget = 0;  // bytes a global ray tree may use (0 = device max)
    enum class Accel { None, Bv, Grid, Bvh, Wide, Cwbvh };
    Accel accel = Accel::Bv;  // how rays find triangles
    bool countRays = false;   // count rays by type on the device (slower; benchmarks)
    // Split frames into row tiles so no launch runs past this (display watchdogs); 0 = off.
    double maxLaunchMs = 0;
    // The values of the options pipelines declare for themselves (PipelineInfo::options), by
    // name; an option not set has its declared default. Each pipeline reads its own.
    PipelineOptionValues pipelineOptions;
    // Render only rows [rowBegin, rowEnd) of the frame (rowEnd 0: every row); the other rows of
    // the image returned are unspecified. Pipelines whose registry entry says supports.rowWindow
    // render just those rows (the viewer's progressive frames); the others render every row.
    int rowBegin = 0, rowEnd = 0;
    int lastRow() const { return rowEnd > 0 ? rowEnd : height; }  // one past the window
};

struct Environment {
    dev::Float3 zenith{0.35f, 0.55f, 0.95f};
    dev::Float3 horizon{0.85f, 0.9f, 1.0f};
    dev::Float3 ground{0.3f, 0.27f, 0.25f};
    // Cubemap faces in the order +x, -x, +y, -y, +z, -z; each cubemapSize^2 RGB texels, row-major,
    // top row first. Empty = sky gradient.
    int cubemapSize = 0;
    std::vector<float> cubemap;
};

// Which Scene object a device copy of a scene or a cached decision was made from. Every Scene
// takes a new number when it is made, copied or assigned, so a scene loaded where an earlier one
// lay in memory is not taken for it: an address can be reused, a number is not.
class SceneId {
  public:
    SceneId() : value_(next()) {}
    SceneId(const SceneId&) : value_(next()) {}
    SceneId& operator=(const SceneId&) {
        value_ = next();
        return *this;
    }
    uint64_t value() const { return value_; }

  private:
    static uint64_t next();
    uint64_t value_;
};

struct Scene {
    SceneId id;                    // this object, for caches of what was made from it
    std::string name;              // file stem
    std::filesystem::path source;  // file it came from (for messages)
    dev::Camera camera{};
    std::vector<dev::Material> materials;
    std::vector<std::string> materialNames;  // parallel to materials
    std::vector<dev::Sphere> spheres;
    std::vector<dev::Plane> planes;
    std::vector<dev::Triangle> triangles;
    std::vector<dev::MeshInstance> meshes;  // every triangle belongs to exactly one mesh
    std::vector<dev::Light> lights;
    Environment environment;
    RenderOptions defaults;
    // What the loader could not use and rendered differently, for front ends to show
    // ("bunny.mtl not found: the default material"); never an error.
    std::vector<std::string> notes;

    // Branching factor C of the ray tree: 2 when any material is transparent, else 1.
    int branching() const;
    bool hasTransparency() const { return branching() == 2; }
    // Any material with a procedural pattern: only then is core/cl/procedural.cl compiled.
    bool hasProcedural() const;
};

// Nodes per pixel tree: N = (C^(B+1) - 1) / (C - 1), or B + 1 when C = 1.
long long treeNodeCount(int branching, int bounces);

// What a choice made from trial frames depends on: the scene object (its SceneId) and every
// setting but the row window, the launch cap and ray counting, which change how a frame is cut or
// counted, not which way of rendering it is fastest. `--pipeline auto` keeps its design, and the
// persistent megakernel its pixel order, while the key stays the same.
struct FrameKey {
    uint64_t scene = 0;
    int width = 0, height = 0, bounces = 0, shadowSamples = 0, aa = 0;
    bool adaptive = false, robustSphere = false, watertight = false;
    RenderOptions::Offset offset{};
    RenderOptions::Accel accel{};
    size_t memoryBudget = 0;
    PipelineOptionValues pipelineOptions;

    FrameKey() = default;
    FrameKey(const Scene& scene, const RenderOptions& options);
    bool operator==(const FrameKey&) const = default;
};

}  // namespace rt
