// rtlab — `--pipeline auto`: renders a scene with the design that should be fastest for it, and
// says which it chose and why (FrameStats::note and extras). It chooses once per scene and
// settings: the predictor (auto/predict.h: the busy lanes of a sample of warps, traced on the CPU
// before any device work) names the kind of design, and trial frames, timed on the device, pick
// among the designs of that kind (or of every kind, --auto-choice measure).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "auto/predict.h"
#include "core/pipeline.h"
#include "core/pipeline_registry.h"

namespace rt {

// A design auto renders with: a registered pipeline, and the megakernel's layout when it is one.
struct AutoDesign {
    std::string pipeline;  // "mega", "wave", "queue" or "persist" (its schedule chosen: auto)
    std::string layout = "weighted";  // the megakernel's --layout: "tree" or "weighted"
    std::string reason;               // one sentence, with the numbers it rests on
    std::string name() const;         // "mega-weighted", "wave", "queue", "persist"
};

// What the choice knows besides the lanes: the device kind whose fitted rule applies, and the
// scene's needs that rule a design out.
struct AutoContext {
    bool gpuRule = true;    // the rule fitted on the H200's map; false: the CPU's
    bool adaptive = false;  // adaptive anti-aliasing asked for (only the megakernel has it)
    bool waveFits = true;   // the tree wavefront's tree fits one tile (no row tiles)
    bool treeFits = true;   // the megakernel's whole tree fits its private budget
};

// The kind of design the predictor names, as the designs of that kind auto may render with
// (first: the one to take without trial frames) and why.
// Busy lanes either side of kQueueBelowLanes inside which auto times the queue too.
inline constexpr double kUncertainLanes = 1.0;

struct AutoKind {
    std::vector<AutoDesign> designs;
    std::string reason;
};

// The rule. On a GPU: below kQueueBelowLanes busy lanes, a design that keeps lanes busy where
// neighbouring pixels' trees disagree: the queue wavefront, or the persistent megakernel, whose
// schedule (--persistent-schedule auto, from the same lanes) then regroups hits among the lanes
// of a work-group; on the H200's map the queue won most such walls and the regrouped persistent
// megakernel the plain 4 px ones, so auto times both. At or above it, one tree a work-item: the
// weighted megakernel, the report's tree wavefront (when its tree fits one tile) or the
// persistent megakernel (the nested loop on such scenes); the lanes do not say which (the tree
// wavefront won most of the map's coherent walls, the weighted megakernel and the persistent
// one the standard scenes), so auto times them.
// On a CPU, whose work-items run without lock-step lanes: the megakernel (the queue never won the
// CPU map), in the tree layout when it fits. Adaptive anti-aliasing: the megakernel, the only
// design that has it.
// Within kUncertainLanes of the threshold the lanes do not decide (on the H200's map, the walls
// at 27.8 busy lanes went to the queue once and to the tree wavefront once), so every design
// that renders the frame in one piece is timed.
AutoKind chooseKind(const LaneEstimate& estimate, const AutoContext& context);

class AutoPipeline : public Pipeline {
  public:
    // Renders with the pipelines `registry` makes (the filled registry, pipelines/registry.h);
    // auto names none of their types.
    AutoPipeline(ClContext& cl, const PipelineRegistry& registry);
    ~AutoPipeline() override;
    const char* name() const override { return "auto"; }
    Image render(const Scene& scene, const RenderOptions& options) override;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace rt
