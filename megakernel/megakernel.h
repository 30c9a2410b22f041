// rtlab — host driver of the megakernel (megakernel/megakernel.cl): one launch per frame.
#pragma once

#include <memory>

#include "core/launch_planner.h"
#include "core/pipeline.h"

namespace rt {

class MegakernelPipeline : public Pipeline {
  public:
    explicit MegakernelPipeline(ClContext& cl) : cl_(cl) {}
    // Keeps the context's device-memory tally true.
    ~MegakernelPipeline() override { cl_.release(imageBytes_ + centerBytes_); }
    const char* name() const override { return "mega"; }
    Image render(const Scene& scene, const RenderOptions& options) override;

    // The defines the program is built with (tests check them).
    static std::vector<std::string> defines(const Scene& scene, const RenderOptions& options);

  private:
    ClContext& cl_;
    std::unique_ptr<DeviceScene> scene_;
    cl::Buffer image_, centers_;
    size_t imageBytes_ = 0, centerBytes_ = 0;
    LaunchPlanner planner_;
};

}  // namespace rt
