// rtlab — host driver of the wavefront pipeline (wavefront/tree/wavefront.cl): trace, image and reset
// kernels around a global ray tree of W x rows x N nodes, in row tiles when it must.
#pragma once

#include <memory>

#include "core/launch_planner.h"
#include "core/pipeline.h"

namespace rt {

class WavefrontPipeline : public Pipeline {
public:
    explicit WavefrontPipeline(ClContext& cl) : cl_(cl) {}
    ~WavefrontPipeline() override { cl_.release(treeBytes_ + imageBytes_); }  // keep the device-memory tally true
    const char* name() const override { return "wave"; }
    Image render(const Scene& scene, const RenderOptions& options) override;

    // Rows per tile for a frame, given the budget for the tree buffer (bytes). Throws rt::Error
    // naming the bounce limit that would fit when not even one row does.
    static int tileRows(int width, int height, int branching, int bounces, size_t budget,
                        const std::string& budgetName);
    // Row tiles a frame of `height` rows needs at `rows` rows per tile: the one place it is counted.
    static int tileCount(int height, int rows) { return (height + rows - 1) / rows; }

private:
    ClContext& cl_;
    std::unique_ptr<DeviceScene> scene_;
    cl::Buffer tree_, image_;
    size_t treeBytes_ = 0, imageBytes_ = 0;
    bool needsClear_ = false;  // a new tree buffer whose flags are not yet cleared
    LaunchPlanner planner_;
};

}  // namespace rt
