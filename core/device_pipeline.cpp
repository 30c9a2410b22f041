// rtlab — the shared part of device pipelines (device_pipeline.h).
#include "core/device_pipeline.h"

#include <chrono>

#include "core/error.h"
#include "core/kernel_resources.h"

namespace rt {

bool DeviceBuffer::ensure(ClContext& cl, size_t bytes, const std::string& what) {
    if (cl_ == &cl && bytes_ == bytes) return false;
    reset();
    buffer_ = cl.allocate(bytes, CL_MEM_READ_WRITE, what);
    cl_ = &cl;
    bytes_ = bytes;
    return true;
}

void DeviceBuffer::reset() {
    if (cl_) cl_->release(bytes_);
    buffer_ = cl::Buffer();
    bytes_ = 0;
    cl_ = nullptr;
}

Image DevicePipeline::render(const Scene& scene, const RenderOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    checkOptions(scene, options);
    stats_ = {};
    Image image = renderFrame(scene, options);
    stats_.hostMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return image;
}

cl::Program DevicePipeline::program(const std::string& file,
                                    const std::vector<std::string>& defines,
                                    const std::vector<std::string>& options) {
    cl::Program p = cl_.program(file, defines, options);
    stats_.kernelResources = kernelResources(p, cl_.device().device, cl_.lastBuildLog());
    stats_.program = cl_.lastProgramSource();
    return p;
}

std::string DevicePipeline::launchKey(const RenderOptions& o,
                                      const std::vector<std::string>& defines,
                                      const std::vector<std::string>& buildOptions,
                                      const std::string& extra) {
    std::string key = std::to_string(o.width) + "x" + std::to_string(o.height);
    for (const std::string& d : defines) key += " " + d;
    for (const std::string& b : buildOptions) key += " " + b;
    key += " b" + std::to_string(o.bounces) + extra;
    const int first = o.rowBegin, last = o.lastRow();
    if (first != 0 || last != o.height)
        key += " rows " + std::to_string(first) + "-" + std::to_string(last);
    return key;
}

DeviceScene& DevicePipeline::deviceScene(const Scene& scene, RenderOptions::Accel accel) {
    if (!scene_ || !scene_->matches(scene, accel))
        scene_ = std::make_unique<DeviceScene>(cl_, scene, accel);
    stats_.accel = scene_->accelStats();
    return *scene_;
}

cl::Program DevicePipeline::rayLoopProgram(const std::string& file,
                                           const std::vector<std::string>& defines,
                                           const std::vector<std::string>& options,
                                           const RenderOptions& o,
                                           const std::vector<std::string>& nvidiaDefines) {
    countLanes_ = false;
    if (!cl_.device().nvidia()) return program(file, defines, options);
    std::vector<std::string> nvidia = defines;
    nvidia.insert(nvidia.end(), nvidiaDefines.begin(), nvidiaDefines.end());
    if (o.countRays) nvidia.push_back("RT_COUNT_LANES");
    if (nvidia.size() == defines.size()) return program(file, defines, options);
    // A build the driver refused once is not tried again for every frame.
    std::string key = file;
    for (const std::string& d : nvidia) key += " -D" + d;
    for (const std::string& x : options) key += " " + x;
    if (refusedBuilds_.count(key)) return program(file, defines, options);
    try {
        cl::Program p = program(file, nvidia, options);
        countLanes_ = o.countRays;
        return p;
    } catch (const Error&) {
        refusedBuilds_.insert(key);
        return program(file, defines, options);
    }
}

void DevicePipeline::startRayCount(const RenderOptions& options) {
    if (options.countRays) scene_->resetRayCounts(cl_.queue());
}

void DevicePipeline::finishRayCount(const RenderOptions& options) {
    if (!options.countRays) return;
    stats_.rays = scene_->readRayCounts(cl_.queue());
    stats_.raysCounted = true;
    if (countLanes_) {
        // Mean busy lanes of a 32-lane warp over the steps of its ray loop.
        const WarpCounts w = scene_->readWarpCounts(cl_.queue());
        stats_.extras["warp_steps"] = double(w.steps);
        stats_.extras["warp_lanes_active"] =
            w.steps ? double(w.lanesActive) / double(w.steps) : 0.0;
        // The pipeline's phase clocks, where its kernels were built with them (in millions of
        // cycles, summed over warps), under the names it gives them.
        const std::vector<std::string> names = phaseNames();
        for (size_t i = 0; i < names.size() && i < size_t(RT_PHASES); ++i)
            if (w.phases[i] != 0) stats_.extras["phase_mcycles_" + names[i]] = w.phases[i] * 64e-6;
    }
}

}  // namespace rt
