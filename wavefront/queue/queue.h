// rtlab — host driver of the queue wavefront (wavefront/queue/queue.cl, issue 14): a pool of ray
// records sized by --pool, not by pixels x tree nodes, refilled with camera rays as paths end;
// each bounce runs extend, shadow, one shade kernel per material class, a prefix-sum compaction
// and the per-pixel sums. See wavefront/queue/README.md for the design and its measurements.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "core/pipeline.h"

namespace rt {

// The pool's device buffers. `rays` is the queue of live rays, `staging` holds the children of
// the bounce (C slots per ray) until they are compacted back into `rays`.
struct QueueBuffers {
    struct Rays {
        cl::Buffer origin, dir, weight, pixel, meta;
    };
    Rays rays, staging;
    cl::Buffer nodes, contrib, children, offsets, blockSums, classQueues, shadowQueue, retry,
        counters, sums, image;
    size_t pool = 0, pixels = 0;
    int branching = 0;
    size_t poolBytes = 0, imageBytes = 0;  // as tallied in the ClContext
};

class QueuePipeline : public Pipeline {
public:
    explicit QueuePipeline(ClContext& cl) : cl_(cl) {}
    ~QueuePipeline() override;
    PipelineKind kind() const override { return PipelineKind::Queue; }
    Image render(const Scene& scene, const RenderOptions& options) override;

    // Ray slots a frame uses: --pool, else a size chosen from the device (and --memory-budget);
    // never fewer than C^B, the most rays one path can hold at once. Throws rt::Error when
    // --pool is below that.
    static size_t poolSize(const DeviceInfo& device, int branching, int bounces,
                           const RenderOptions& options);
    // Device bytes per pool slot: ray fields, staging, node, queues (independent of B). A pool
    // takes pool * bytesPerRay + 4 + RT_Q_WORDS * 4 bytes (FrameStats::poolBytes).
    static size_t bytesPerRay(int branching);
    // Work-group size of the scan (and the most any queue kernel uses): a power of two.
    static int groupSize(const DeviceInfo& device);

private:
    void prepareBuffers(size_t pool, int branching, size_t pixels);
    void releaseBuffers();

    ClContext& cl_;
    std::unique_ptr<DeviceScene> scene_;
    QueueBuffers buf_;
};

}  // namespace rt
