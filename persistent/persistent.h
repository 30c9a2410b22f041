// rtlab — host driver of the persistent megakernel (persistent/persistent.cl): a fixed number of
// work-groups sized to fill the device, each work-item taking pixels from a global counter.
#pragma once

#include "core/device_pipeline.h"
#include "core/launch_planner.h"

namespace rt {

class PersistentPipeline : public DevicePipeline {
  public:
    explicit PersistentPipeline(ClContext& cl) : DevicePipeline(cl) {}
    const char* name() const override { return "persist"; }

    // Work-items of one launch: --persistent-groups work-groups of `local` per compute unit.
    static size_t workItems(const DeviceInfo& device, const RenderOptions& options, size_t local);

  private:
    Image renderFrame(const Scene& scene, const RenderOptions& options) override;

    DeviceBuffer image_, next_;
    LaunchPlanner planner_;
};

}  // namespace rt
