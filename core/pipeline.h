// rtlab — what the pipelines share on the host: the Pipeline interface that `rtlab render`, the
// benchmarks and the viewer drive (pipelines are found by name in core/pipeline_registry.h), the
// device copy of a scene, and the feature defines that make each program model no more than its
// scene needs.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/image.h"
#include "core/kernel.h"
#include "core/launch_planner.h"
#include "core/scene.h"

namespace rt {

// Rays by type (RT_RAY_* in core/types.h): primary, reflection, refraction, shadow.
using RayCounts = std::array<uint64_t, RT_RAY_TYPES>;
// A ray loop's SIMD use, counted on the device (RT_COUNT_LANES): lanes active summed over warp
// steps, and the steps; lanesActive / steps is the mean number of busy lanes of a warp.
struct WarpCounts {
    uint64_t lanesActive = 0, steps = 0;
    // A pipeline's phase clocks (RT_PHASES slots, core/types.h), in units of 64 cycles; zero
    // unless its kernels were built with them.
    uint64_t phases[RT_PHASES] = {};
};
const char* rayTypeName(int type);  // "primary", "reflection", "refraction", "shadow"
// --offset names: fixed, scaled, bound. parseOffset throws rt::Error naming the flag.
RenderOptions::Offset parseOffset(const std::string& name);
const char* offsetName(RenderOptions::Offset offset);

// What one frame cost, in terms every pipeline shares; what only one pipeline has goes in extras.
struct FrameStats {
    // Device time per kernel, summed over every launch of the frame (profiling events), in ms.
    std::vector<std::pair<std::string, double>> kernelMs;
    double deviceMs = 0;  // sum of kernelMs
    double hostMs = 0;    // wall time of render() on the host
    // Device buffers the frame used, by name, in bytes (the scene's own are in accel).
    std::vector<std::pair<std::string, size_t>> buffers;
    size_t privateBytes = 0;     // private ray storage per work-item (estimate from the layout)
    int tiles = 1;               // row tiles the frame was split into
    int launches = 0;            // kernel launches (time-bounded tiles x passes)
    double longestLaunchMs = 0;  // the longest single launch of the frame (watchdog margin)
    std::string program;         // how the program was obtained: built, disk or memory cache
    // Rays traced on the device by type; filled only when RenderOptions::countRays is set,
    // because the atomics cost time.
    RayCounts rays{};
    bool raysCounted = false;
    // The acceleration structure the frame traversed (DeviceScene::accelStats); its build time
    // is that of the frame that built it, since later frames reuse the device copy.
    AccelStats accel;
    // Pipeline-specific values (numbers or strings), carried as they are into sweep rows.
    nlohmann::json extras = nlohmann::json::object();
    // One line the pipeline wants its user to read about the frame ("auto: chose queue: 13.1
    // busy lanes ..."); front ends print it. Empty for most frames.
    std::string note;
    // Per kernel of the program: registers and spills (NVIDIA), private bytes
    // (core/kernel_resources.h), carried into sweep rows as kernel_resources.
    std::map<std::string, double> kernelResources;
    void addKernel(const std::string& name, double ms);
    void addBuffer(const std::string& name, size_t bytes);
};

struct LaneEstimate;  // the predictor's (auto/predict.h)

class Pipeline {
  public:
    // A chooser that traced the scene's warps hands its estimate (traced in `ms`) to a pipeline
    // that chooses from one too, so that the warps are traced once; most ignore it.
    virtual void useLaneEstimate(const Scene&, const RenderOptions&, const LaneEstimate&,
                                 double /*ms*/) {}
    virtual ~Pipeline() = default;
    // The registered name (PipelineRegistry): "mega".
    virtual const char* name() const = 0;
    // Renders one frame. Device buffers are allocated on the first call and kept while the scene
    // (by address) and the frame size stay the same.
    virtual Image render(const Scene& scene, const RenderOptions& options) = 0;
    const FrameStats& stats() const { return stats_; }
    // Progress of the frame being rendered: work done so far and the frame's total, in the
    // pipeline's own units (rows x passes, pixels x samples), non-decreasing and ending at total.
    // Pipelines that report nothing render as before; front ends draw bars from it.
    using Progress = std::function<void(long long done, long long total)>;
    void setProgress(Progress progress) { progress_ = std::move(progress); }

  protected:
    void reportProgress(long long done, long long total) const {
        if (progress_) progress_(done, total);
    }
    FrameStats stats_;
    Progress progress_;
};

// -D defines for a scene and its options: object kinds present, C, the accuracy switches and the
// acceleration structure. The bounce limit is not among them: kernels read it from the settings
// at run time, so one program serves every B. A program that sizes a private array by B adds
// that size itself (treeNodesDefine, the megakernel's stack).
std::vector<std::string> featureDefines(const Scene& scene, const RenderOptions& options);

// RT_TREE_NODES=N, the size of a whole ray tree of `bounces` levels, for programs that keep one
// in private memory per work-item (the megakernel's tree layout, the shading probe).
std::string treeNodesDefine(const Scene& scene, int bounces);

// The kernel-argument record for a scene, its options and the frame.
dev::RenderSettings makeSettings(const Scene& scene, const RenderOptions& options);

// Validates options against the scene and the shared limits; throws rt::Error naming the flag.
void checkOptions(const Scene& scene, const RenderOptions& options);

// Private memory the tree layout needs per work-item, and the most rtlab lets it use. The cap is
// rtlab's own, not a limit devices report (OpenCL has no query for private memory per
// work-item). A private array that large lives in off-chip memory anyway, where the weighted
// layout needs none: past the cap, a clear error that names the highest B that fits.
// nodeBytes: a Node's size in the scene's programs (dev::nodeBytes of its light count).
size_t treePrivateBytes(int branching, int bounces, size_t nodeBytes = sizeof(dev::Node));
constexpr size_t kPrivateTreeLimit = 256 * 1024;
// Throws when the tree of N nodes does not fit kPrivateTreeLimit, naming the bounce limit that
// fits. `who` names the kernel that keeps the tree, as the user knows it; `hint`, appended to
// the message, may name another way out that the kernel's own options offer.
void checkPrivateTree(int branching, int bounces, const std::string& who,
                      const std::string& hint = "", size_t nodeBytes = sizeof(dev::Node));

// The scene's object arrays on the device, with the acceleration structure of one --accel mode.
class DeviceScene {
  public:
    DeviceScene(ClContext& cl, const Scene& scene, RenderOptions::Accel accel);
    ~DeviceScene();
    DeviceScene(const DeviceScene&) = delete;
    DeviceScene& operator=(const DeviceScene&) = delete;
    // Sets the scene arguments (RT_SCENE_PARAMS in core/cl/scene.cl) by name, with the given
    // settings (their grid field is filled here); the kernel's own arguments are its caller's.
    void setArgs(Kernel& kernel, const dev::RenderSettings& settings) const;
    // Device ray counters (RenderOptions::countRays): zero them before a frame, read them after.
    void resetRayCounts(cl::CommandQueue& queue) const;
    RayCounts readRayCounts(cl::CommandQueue& queue) const;
    WarpCounts readWarpCounts(cl::CommandQueue& queue) const;  // zeroed by resetRayCounts
    // The counters themselves (RT_RAY_TYPES ray counters, then the warp counters and the phase
    // clocks), for a kernel that adds to them outside RT_SCENE_PARAMS.
    const cl::Buffer& rayCountBuffer() const { return rayCounts_; }
    // True when this copy was made from `scene` with `accel` (by its SceneId: scenes are not
    // mutated while a pipeline holds them, except the camera, which travels in the settings).
    bool matches(const Scene& scene, RenderOptions::Accel accel) const {
        return source_ == scene.id.value() && accel_ == accel;
    }
    // Which structure was built, in how long, and how large it is (for FrameStats::accel).
    const AccelStats& accelStats() const { return stats_; }

  private:
    ClContext& cl_;
    uint64_t source_;  // the Scene's id (SceneId), not its address, which a later scene may reuse
    RenderOptions::Accel accel_;
    AccelStats stats_;
    dev::Grid grid_{};
    size_t bytes_ = 0;  // allocated through cl_, released on destruction
    cl::Buffer spheres_, planes_, triangles_, meshes_, kdops_, lights_, materials_, cubemap_, bvh_,
        cells_, rayCounts_;
};

// 2D launch geometry: global size rounded up to the local size on GPUs, runtime's choice on CPUs.
struct Launch {
    cl::NDRange global, local;
};
Launch launch2d(const DeviceInfo& device, int width, int rows);

// Part of a row is launched in steps of launch2d's work-group width, one work-group row high.
int columnStep(const DeviceInfo& device);

// The NDRange of one tile the LaunchPlanner planned: whole rows as launch2d shapes them, or
// columns [col0, col0 + cols) of one row, placed by the global offset so that get_global_id(0)
// is the pixel's x (kernels drop x >= width).
struct TileRange {
    cl::NDRange offset, global, local;
};
TileRange tileRange(const DeviceInfo& device, int width, const LaunchTile& tile);

}  // namespace rt
