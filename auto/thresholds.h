// rtlab — the choosers' fitted thresholds, per device kind, each with the data it was fitted on:
// the predictor's rule (auto/predict.h, predictDesign), `--pipeline auto` (auto.cpp) and the
// persistent megakernel's schedule under --persistent-schedule auto (auto/persist_choice.h).
#pragma once

namespace rt {

struct FittedThresholds {
    // Below this many busy lanes of 32 a megakernel's warp leaves too many lanes idle: the queue
    // wavefront wins, and the persistent megakernel regroups.
    double queueBelowLanes;
    // From this many objects a warp's camera rays hit, a warp shades several procedural patterns:
    // the persistent megakernel regroups though its lanes are busy.
    double regroupFromObjects;
};

// A GPU (lock-step warps of 32). Fitted on an NVIDIA H200 (driver 580.159.04):
// queueBelowLanes on the crossover map's 32 walls and the standard scenes, the threshold that
// names the faster of the megakernel and the queue on the most scenes
// (results/nvidia-h200/predictor-196a299/, scripts/predict_eval.py); regroupFromObjects on the map
// at dc782c6 (results/nvidia-h200/persist-auto-dc782c6/): the nested loop was the best schedule on
// every scene at 29.5 predicted lanes or more and at most 1.4 objects a warp, a regrouped one on
// every wall at 26.5 lanes or fewer and on the two coherent walls of 16 px spheres (1.8 objects a
// warp).
inline constexpr FittedThresholds kGpuThresholds{27.8, 1.6};

// A CPU (PoCL; work-items without lock-step lanes). Fitted the same way on the PoCL map
// (results/pocl-cpu-skylake-avx512-intel-r-xeon-r-processor/map-pocl-196a299/predictor.md): the
// queue never won, so no busy-lane count names
// it. The persistent megakernel's schedule was not fitted on a CPU; it takes the GPU's objects
// threshold.
inline constexpr FittedThresholds kCpuThresholds{0.0, 1.6};

}  // namespace rt
