// rtlab — host driver of the megakernel (megakernel/megakernel.cl): one launch per frame.
#pragma once

#include <memory>

#include "core/device_pipeline.h"
#include "core/launch_planner.h"

namespace rt {

class MegakernelPipeline : public DevicePipeline {
  public:
    explicit MegakernelPipeline(ClContext& cl) : DevicePipeline(cl) {}
    const char* name() const override { return "mega"; }

    // The defines the program is built with (tests check them).
    static std::vector<std::string> defines(const Scene& scene, const RenderOptions& options);
    // The compiler options beside them: the register cap (--max-registers), on NVIDIA only.
    std::vector<std::string> buildOptions(const RenderOptions& options) const;
    // Private ray storage per work-item in the layout `options` asks for: the whole tree, or
    // the weighted stack's pending rays (64 bytes each).
    static size_t privateBytes(const Scene& scene, const RenderOptions& options);

  private:
    Image renderFrame(const Scene& scene, const RenderOptions& options) override;

    DeviceBuffer image_, centers_;
    LaunchPlanner planner_;
};

}  // namespace rt
