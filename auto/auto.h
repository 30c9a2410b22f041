// rtlab — `--pipeline auto`: renders a scene with the design that should be fastest for it, and
// says which it chose and why (FrameStats::extras). It chooses once per scene and settings, either
// from the predictor (core/predict.h: the busy lanes of a sample of warps, traced on the CPU
// before any device work) or from a trial frame of each candidate, timed on the device.
#pragma once

#include <memory>
#include <string>

#include "core/pipeline.h"
#include "core/predict.h"
#include "megakernel/megakernel_options.h"

namespace rt {

// A design auto renders with: a registered pipeline, and the megakernel's layout when it is one.
struct AutoDesign {
    std::string pipeline;  // "mega", "wave" or "queue"
    MegaLayout layout = MegaLayout::Weighted;
    std::string reason;        // one sentence, with the numbers it rests on
    std::string name() const;  // "mega-weighted", "wave", "queue"
};

// What the choice knows besides the lanes: the device kind whose fitted rule applies, and the
// scene's needs that rule a design out.
struct AutoContext {
    bool gpuRule = true;    // the rule fitted on the H200's map; false: the CPU's
    bool adaptive = false;  // adaptive anti-aliasing asked for (only the megakernel has it)
    bool waveFits = true;   // the tree wavefront's tree fits one tile (no row tiles)
    bool treeFits = true;   // the megakernel's whole tree fits its private budget
};

// The rule. On a GPU: the queue wavefront below kQueueBelowLanes busy lanes; at or above it the
// report's tree wavefront when its tree fits one tile (it won 18 of the map's 19 coherent walls),
// else the weighted megakernel. On a CPU, whose work-items run without lock-step lanes: the
// megakernel (the queue never won the CPU map; the others tie there), in the tree layout when it
// fits. Adaptive anti-aliasing forces the megakernel, the only design that has it.
AutoDesign chooseDesign(const LaneEstimate& estimate, const AutoContext& context);

class AutoPipeline : public Pipeline {
  public:
    explicit AutoPipeline(ClContext& cl);
    ~AutoPipeline() override;
    const char* name() const override { return "auto"; }
    Image render(const Scene& scene, const RenderOptions& options) override;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rt
