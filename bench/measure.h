// rtlab bench — measuring one cell: warm-up frames, then timed frames whose device time is the
// sum of the frame's kernels by OpenCL profiling events, reported as medians; then, untimed, one
// frame with the device ray counters (their atomics would distort the timed frames).
// Used by rtlab-bench (Google Benchmark and --sweep) and by `rtlab sweep`.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/image.h"
#include "core/pipeline.h"
#include "core/scene.h"
#include "pipelines/registry.h"

namespace rt::bench {

struct Measurement {
    bool ok = false;
    std::string error;                        // why the cell could not be measured (ok = false)
    FailureKind failure = FailureKind::None;  // its kind, as thrown
    int frames = 0;                           // timed frames
    double deviceMs = 0;  // median over the timed frames of the kernels' summed time
    double deviceMsMin = 0, deviceMsMax = 0;
    double wallMs = 0;            // median host wall time of render(), read-back included
    std::vector<double> frameMs;  // device ms of each timed frame, in round order
    std::vector<std::pair<std::string, double>> kernelMs;  // median per kernel name
    size_t deviceBytes = 0;  // global memory the pipeline allocated for this frame
    std::vector<std::pair<std::string, size_t>> buffers;  // FrameStats::buffers
    size_t privateBytes = 0;
    int tiles = 1, launches = 0;
    std::map<std::string, double> kernelResources;  // FrameStats::kernelResources
    double longestLaunchMs = 0;  // the longest single kernel launch of any timed frame
    RayCounts rays{};            // by RT_RAY_* type
    bool raysCounted = false;
    double mrays = 0;  // million rays per second of device time (when counted)
    nlohmann::json extras = nlohmann::json::object();  // FrameStats::extras, counting frame's last
    double accelBuildMs = 0;  // host wall time of the acceleration structure's build
    // Host wall time this cell spent building or loading OpenCL programs (ClContext's counts):
    // the first cell of a program pays it, later ones find the program in the context.
    double programMs = 0;
    Image image;  // the last timed frame, when asked for
};

// Never throws for a cell that fails (CL error, a limit): the Measurement says why.
Measurement measureCell(ClContext& cl, const Scene& scene, const std::string& pipeline,
                        const RenderOptions& options, int warmup, int repeats, bool countRays,
                        bool keepImage);

// Several variants of one scene (pipelines, accels) with their timed frames interleaved, round
// by round (mega, wave, mega, wave, ...), so that their ratios see the same machine state; the
// frames of one round are comparable one to one (Measurement::frameMs). One result per variant.
struct Variant {
    std::string pipeline;  // a registered name
    RenderOptions options;
};
// frameCapS > 0 bounds a variant's timed frames: once they add up to more than that many seconds
// of wall time (or its last warm-up frame alone took longer), it stops after at least one.
std::vector<Measurement> measureCells(ClContext& cl, const Scene& scene,
                                      const std::vector<Variant>& variants, int warmup, int repeats,
                                      bool countRays, bool keepImage, double frameCapS = 0);

// Fills mrays from the ray counts and the median device time.
void deriveRayCounters(Measurement& m);

// The median of a non-empty list.
double median(std::vector<double> v);

// Short, filesystem-safe name for a device: "nvidia-h100-80gb-hbm3", "pocl-amd-epyc-...".
std::string deviceSlug(const DeviceInfo& device);

// What every row carries about where it ran and what was built.
nlohmann::json deviceJson(const DeviceInfo& device);

// Object counts of a scene, for the results tables.
nlohmann::json sceneJson(const Scene& scene);

}  // namespace rt::bench
