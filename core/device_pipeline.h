// rtlab — what every device pipeline shares, so that a pipeline's folder holds only its own
// schedule: the frame's host time and fresh statistics (render), program builds with their
// statistics, the scene's device copy kept while the scene and structure stay, device buffers
// kept from frame to frame and tallied in the context, and the device ray counters.
#pragma once

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/pipeline.h"

namespace rt {

// A device buffer kept from frame to frame, its bytes tallied in its context while it lives.
class DeviceBuffer {
  public:
    DeviceBuffer() = default;
    ~DeviceBuffer() { reset(); }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;

    // Makes the buffer `bytes` long, allocating only when that changes; the old buffer is
    // forgotten first, so that after a failed allocation no stale size names a buffer that is
    // gone. Returns true when it allocated. `what` names the buffer in an allocation error.
    bool ensure(ClContext& cl, size_t bytes, const std::string& what);
    void reset();
    const cl::Buffer& get() const { return buffer_; }
    size_t bytes() const { return bytes_; }

  private:
    ClContext* cl_ = nullptr;
    cl::Buffer buffer_;
    size_t bytes_ = 0;
};

class DevicePipeline : public Pipeline {
  public:
    // Checks the options every pipeline shares, starts the frame's statistics afresh, renders
    // it (renderFrame) and records its host wall time.
    Image render(const Scene& scene, const RenderOptions& options) final;

  protected:
    explicit DevicePipeline(ClContext& cl) : cl_(cl) {}
    virtual Image renderFrame(const Scene& scene, const RenderOptions& options) = 0;

    // The program of `file` with these defines (ClContext::program), with how it was obtained
    // and its kernels' resources recorded in the frame's statistics.
    cl::Program program(const std::string& file, const std::vector<std::string>& defines,
                        const std::vector<std::string>& options = {});
    // The key a frame's launch plan is kept under (LaunchPlanner::begin), built in one place for
    // every pipeline that plans launches by rows: the frame's size, its program's defines and
    // build options, the bounce limit (one program may serve several; costs differ), `extra`
    // (what else the pipeline's costs depend on, e.g. " g<work-items>"), and a row window,
    // which has a profile of its own (the planner's is by row from the first one rendered).
    static std::string launchKey(const RenderOptions& o, const std::vector<std::string>& defines,
                                 const std::vector<std::string>& buildOptions,
                                 const std::string& extra = "");
    // The scene's device copy with the structure of `accel`, made again only when either
    // changed; its structure's statistics go into the frame's.
    DeviceScene& deviceScene(const Scene& scene, RenderOptions::Accel accel);
    // program() for a kernel whose ray loop counts its warps' busy lanes (RT_COUNT_WARP_STEP):
    // on NVIDIA, a counting frame's program is built with RT_COUNT_LANES (inline PTX) and
    // `nvidiaDefines` (further PTX the kernel uses there); should the driver refuse either, the
    // program without them, and the frame counts rays alone.
    cl::Program rayLoopProgram(const std::string& file, const std::vector<std::string>& defines,
                               const std::vector<std::string>& options, const RenderOptions& o,
                               const std::vector<std::string>& nvidiaDefines = {});
    // The device ray counters, for a counting frame (RenderOptions::countRays): zeroed before
    // it, read into the frame's statistics after it (and the busy lanes, when the program from
    // rayLoopProgram counts them). Both do nothing for other frames.
    void startRayCount(const RenderOptions& options);
    void finishRayCount(const RenderOptions& options);
    // The names of the phase clocks the pipeline's kernels may keep (core/types.h, RT_PHASES
    // slots, in slot order), which finishRayCount gives the counts it reads; none by default.
    virtual std::vector<std::string> phaseNames() const { return {}; }

    ClContext& cl_;
    std::unique_ptr<DeviceScene> scene_;

  private:
    bool countLanes_ = false;              // the last rayLoopProgram counts busy lanes
    std::set<std::string> refusedBuilds_;  // rayLoopProgram's NVIDIA builds the driver refused
};

}  // namespace rt
