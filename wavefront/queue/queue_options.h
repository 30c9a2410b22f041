// rtlab — the queue wavefront's own options (--queue-launch, --pool, --queue-packets,
// --queue-shade, --queue-group, --queue-local-pad), declared
// in its registry entry (core/pipeline_options.h) and read back here, typed, from
// RenderOptions::pipelineOptions. Front ends know them only through the declarations.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/pipeline_options.h"
#include "core/scene.h"

namespace rt {

// How each bounce's launches are sized. Readback: the host reads the counts once per bounce
// (blocking). Device: every bounce is enqueued at once over a bound the host knows, and each
// kernel reads its real count from the device (wavefront/queue/README.md).
enum class QueueLaunchMode { Readback, Device };
// Whether the extend and shadow queues are traced 16 rays per work-item (packets of the wide
// BVH, for CPU devices). Auto: when the device is a CPU, --accel wide and the scene has no
// spheres outside the BVH's reach (wavefront/queue/README.md); On refuses otherwise.
enum class QueuePacketMode { Auto, On, Off };
// Which rays share a shade launch (queue_layout.h, RT_Q_SHADE_*; wavefront/queue/README.md):
// one queue per material class (the default), the procedural class split further into one
// queue and one kernel per pattern, or every hit in one launch after a sort by material.
enum class QueueShadeMode { Class, Pattern, Sort };

// The declarations, in the order cell keys list them.
std::vector<PipelineOption> queueOptions();
// The forms the smoke check and the equivalence tests run: the defaults, and "padded" (groups of
// 64 with 16 KiB of --queue-local-pad).
std::vector<PipelineVariant> queueVariants();

QueueLaunchMode queueLaunch(const RenderOptions& options);
void setQueueLaunch(RenderOptions& options, QueueLaunchMode mode);
// Ray slots in the pool; 0: chosen from the device (QueuePipeline::poolSize).
size_t queuePool(const RenderOptions& options);
void setQueuePool(RenderOptions& options, size_t rays);  // 0: back to the device's choice
QueuePacketMode queuePackets(const RenderOptions& options);
void setQueuePackets(RenderOptions& options, QueuePacketMode mode);
QueueShadeMode queueShade(const RenderOptions& options);
void setQueueShade(RenderOptions& options, QueueShadeMode mode);
// Work-items per group of the queue's kernels; 0: chosen from the device
// (QueuePipeline::groupSize).
int queueGroup(const RenderOptions& options);
void setQueueGroup(RenderOptions& options, int items);  // 0: back to the device's choice
// A diagnostic: bytes of local memory that hold nothing in each group of the per-ray stage kernels
// (extend, shadow, shade), so that fewer groups are resident on a compute unit at once.
size_t queueLocalPad(const RenderOptions& options);
void setQueueLocalPad(RenderOptions& options, size_t bytes);

// Names as the flags take them: readback, device; auto, on, off; class, pattern, sort. The parsers
// throw rt::Error naming the flag ("--queue-launch up: must be readback or device").
QueueLaunchMode parseQueueLaunch(const std::string& name);
const char* queueLaunchName(QueueLaunchMode mode);
QueuePacketMode parseQueuePackets(const std::string& name);
const char* queuePacketsName(QueuePacketMode mode);
QueueShadeMode parseQueueShade(const std::string& name);
const char* queueShadeName(QueueShadeMode mode);

}  // namespace rt
