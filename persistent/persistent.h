// rtlab — host driver of the persistent megakernel: a fixed number of work-groups sized to fill
// the device, each work-item taking pixels from a global counter, in one of the schedules of
// schedules.h (--persistent-schedule), or the one chosen per scene (auto, persistent_auto.cpp).
#pragma once

#include <optional>
#include <string>

#include "auto/persist_choice.h"
#include "auto/predict.h"
#include "core/device_pipeline.h"
#include "core/launch_planner.h"
#include "persistent/schedules.h"
#include "wavefront/bounce/bounce.h"

namespace rt {

// Sets --persistent-schedule auto in `options` (what `--pipeline auto` renders the persistent
// megakernel with).
void setPersistentScheduleAuto(RenderOptions& options);

// The register cap (-cl-nv-maxrregcount) of a build whose work-groups have `lanes` work-items on
// `device`. A group's work-items share the registers of one multiprocessor, so a kernel built with
// more a work-item than fit cannot launch in such groups. Returns `asked`
// (--persistent-max-registers, 0: the compiler's choice) where it fits; where nothing was asked
// and the compiler's choice might not fit, the most that does (as CUDA's __launch_bounds__ caps a
// kernel); refuses an asked cap that does not fit, naming both flags. Devices that do not say how
// many registers a group shares (DeviceInfo::registersPerGroup 0) get `asked`.
long long persistentRegisterCap(const DeviceInfo& device, size_t lanes, long long asked);

class PersistentPipeline : public DevicePipeline {
  public:
    explicit PersistentPipeline(ClContext& cl) : DevicePipeline(cl) {}
    const char* name() const override { return "persist"; }

    // --persistent-schedule auto: chooses from this estimate of the scene's warps (traced in
    // `ms`) instead of tracing them again, while the scene and settings stay the same.
    void useLaneEstimate(const Scene& scene, const RenderOptions& options,
                         const LaneEstimate& estimate, double ms) override {
        estimates_.put(scene, options, estimate, ms);
    }

    // One frame's schedule and its settings: the options' own, or auto's choice.
    struct Run {
        const PersistSchedule* schedule = nullptr;
        long long lanes = 0;      // 0: the schedule's default, lowered to what the kernel runs
        long long groups = 4;     // work-groups a compute unit
        long long registers = 0;  // the asked register cap; 0 the compiler's, or what fits
    };

  private:
    Image renderFrame(const Scene& scene, const RenderOptions& options) override;
    // The phase clocks' names (phases.h).
    std::vector<std::string> phaseNames() const override;
    // The frame in one schedule.
    Image renderRun(const Scene& scene, const RenderOptions& options, const Run& run);

    // --persistent-schedule auto (persistent_auto.cpp): the schedule the traced warps call for,
    // and, where they cannot tell, the faster in trial frames.
    Run chooseSchedule(const Scene& scene, const RenderOptions& options);
    // A choice the traced warps cannot make, made by trial frames once per scene and settings:
    // the candidate chosen, each one's best time (null where the device refused it) and why a
    // refused one was, and the scene and settings it was made for.
    struct TrialChoice {
        std::optional<FrameKey> key;
        std::string chosen;
        nlohmann::json trialsMs, refused;
    };
    struct TrialCandidate {
        std::string name;
        Run run;
    };
    // Renders two frames of each candidate (the first may pay for building its program) and
    // keeps the fastest in `choice`, unless `choice` was made for `base`'s scene and settings
    // already; returns whether it timed them. A candidate that fails (an rt::Error: scratch past
    // the device, a launch it refuses) is left out with its message; where all do, the last
    // failure is thrown.
    bool decide(TrialChoice& choice, const Scene& scene, const RenderOptions& base,
                const std::vector<TrialCandidate>& candidates);

    DeviceBuffer image_, next_;
    BounceScratch bounce_;
    LaunchPlanner planner_;
    LaneEstimateCache estimates_;  // --persistent-schedule auto's, one trace per scene
    TrialChoice order_, loop_;     // the nested loop's strip order; the regrouped or bounce loop
};

}  // namespace rt
