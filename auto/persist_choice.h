// rtlab — the persistent megakernel's schedule for a scene under --persistent-schedule auto, from
// the predictor's estimate of its warps (auto/predict.h): a chooser, kept with the others in
// auto/. The pipeline (persistent/persistent_auto.cpp) times what the estimate cannot tell.
#pragma once

#include <string>

#include "auto/predict.h"
#include "auto/thresholds.h"

namespace rt {

// --persistent-schedule auto: the schedule a scene's predicted warps call for (auto/predict.h).
// Where neighbouring pixels' trees disagree (fewer busy lanes than the predictor's queue
// threshold), or where a warp's camera rays hit several objects and so shade several procedural
// patterns, two regrouped work-groups of 256 lanes a compute unit, capped at 128 registers so that
// both fit on NVIDIA, sort their hits by pattern each step; elsewhere the nested loop keeps a
// work-group's lanes on neighbouring pixels. Fitted on the H200's map: the nested loop was the
// best schedule on every scene at 29.5 predicted lanes or more and at most 1.4 objects a warp, a
// regrouped one on every wall at 26.5 lanes or fewer and on the two coherent walls of 16 px
// spheres (1.8 objects a warp).
// The thresholds are the GPU's (auto/thresholds.h, where the data they were fitted on are named).
inline constexpr double kRegroupBelowLanes = kGpuThresholds.queueBelowLanes;
inline constexpr double kRegroupFromObjects = kGpuThresholds.regroupFromObjects;

struct PersistChoice {
    bool regroup = false;  // else the nested loop
    std::string reason;    // one sentence with the lanes or objects it rests on
    const char* name() const { return regroup ? "regrouped" : "nested"; }
};

PersistChoice choosePersistentSchedule(const LaneEstimate& estimate);

}  // namespace rt
