// rtlab — the bounce loop's scratch on the host: a wavefront inside one persistent launch
// (bounce.cl), launched by the persistent megakernel's driver as its `bounce` and
// `bounce-staged` schedules (persistent/schedules.h). A work-group takes a batch of twice its
// lanes in pixels and traces them bounce by bounce; its rays, terms and (staged) hits wait here.
#pragma once

#include <cstddef>

#include "core/device_pipeline.h"
#include "core/kernel.h"

namespace rt {

// Pixels a work-group of `lanes` takes together: twice its lanes. On the H200 (results/
// nvidia-h200/bounce-b262634/) 512 lanes ran fastest with batches of 1024 (against 2048), and
// 256 lanes with 512 (against 1024 and 2048).
inline constexpr size_t kBounceBatchPerLane = 2;

class BounceScratch {
  public:
    // Sizes the scratch of `groups` work-groups of `lanes` (or refuses, naming the flags, when
    // the device cannot hold it), tallies it in `stats` and sets the kernel's arguments for it.
    void bind(ClContext& cl, Kernel& kernel, FrameStats& stats, const Scene& scene,
              const RenderOptions& options, size_t groups, size_t lanes, bool staged);
    // Frees it (a trial frame's scratch, which can be gigabytes at high bounce limits).
    void reset();

  private:
    DeviceBuffer rays_, terms_, hits_, order_;
};

}  // namespace rt
