// rtlab — host driver of the queue wavefront (wavefront/queue/queue.cl): a pool of ray
// records sized by --pool, not by pixels x tree nodes, refilled with camera rays as paths end;
// each bounce runs extend, shadow, the shade kernels (one per material class, or per pattern, or
// one over the hits sorted by material: --queue-shade), a prefix-sum compaction
// and the per-pixel sums. See wavefront/queue/README.md for the design and its measurements.
#pragma once

#include <array>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/device_pipeline.h"
#include "core/ray_state.h"
#include "wavefront/queue/queue_options.h"
#include "wavefront/queue/queue_split.h"

namespace rt {

// The pool's device buffers. `rays` is the queue of live rays, `staging` holds the children of
// the bounce (C slots per ray) until they are compacted back into `rays`.
struct QueueBuffers {
    // The per-ray state's fields (core/ray_state.h), one buffer each, and the rays' pixels.
    struct Rays {
#define QUEUE_RAYS_BUFFER(X, field, ...) cl::Buffer field;
        RT_RAY_STATE(QUEUE_RAYS_BUFFER, QUEUE_RAYS_BUFFER, _)
#undef QUEUE_RAYS_BUFFER
        cl::Buffer pixel;
    };
    Rays rays, staging;
    cl::Buffer nodes, contrib, children, offsets, blockSums, shadeQueues, shadowQueue, retry,
        counters, sums, image;
    size_t pool = 0, pixels = 0;
    int branching = 0;
    int queues = 0;  // shade queues of `pool` slots each: RT_Q_CLASSES, or as --queue-shade has
    // --queue-shade sort: a word per material, its hits and then its next slot in the sorted
    // queue (queue_sort.cl). QueuePipeline keeps it (a DeviceBuffer); this is its handle.
    cl::Buffer sortKeys;
    size_t poolBytes = 0, imageBytes = 0;  // as tallied in the ClContext
    // Ray counts (RenderOptions::countRays): the retraced rays by type, then each pixel's rays
    // of its current path by type (queue.cl, Queue_PixelRays); one stub of 4 words otherwise.
    // QueuePipeline keeps it (a DeviceBuffer) across pool sizes; this is its handle.
    cl::Buffer rayTally;
};

// The kernels of the last program, created once and reused frame after frame (with their
// work-group sizes); arguments are set again every frame.
struct QueueKernels {
    cl_program program = nullptr;
    std::map<std::string, Kernel> kernels;
    std::map<std::string, size_t> locals;
};

// What a queue frame did beyond the generic FrameStats (also written to its extras): ray slots and
// device bytes of the pool with its queues and staging (not the image), bounces run, paths cut
// for room and started again, and the rays per bounce (depth 0..B) in each class queue: miss,
// diffuse, mirror, glass, procedural.
struct QueueStats {
    size_t poolRays = 0, poolBytes = 0;
    int iterations = 0;
    long long restartedPaths = 0;
    // Rays by type traced for the paths that were cut and started again (counted frames only):
    // work the queue does beyond the image's rays, which FrameStats::rays holds.
    RayCounts retracedRays{};
    // Launch sizing (--queue-launch): blocking reads and writes the host waited on before the
    // frame's last kernel was enqueued (one per bounce with read-backs, none on the device), the
    // device's time from the first kernel's start to the last one's end, and the part of it in
    // which no kernel ran: the most that sizing launches on the device could save.
    int readbacks = 0;
    double spanMs = 0, idleMs = 0;
    bool fellBack = false;  // device sizing overflowed the pool: rendered again with read-backs
    bool packets = false;   // extend and shadow traced packets (--queue-packets)
    double shadeMs = 0;     // the shade stage's kernels (with --queue-shade sort's sort)
    std::vector<std::array<long long, 5>> queueLengths;  // RT_Q_CLASSES (queue_layout.h)
    // The rays each shade queue held, summed over the frame's bounces, as --queue-shade numbers
    // the queues (queue_layout.h; cut paths' rays too). Read with the counts each bounce reads
    // back: --queue-launch readback only, zero on the device.
    std::array<long long, 9> shadeQueueRays{};  // RT_Q_QUEUES (static_assert in queue.cpp)
};

class QueuePipeline : public DevicePipeline {
  public:
    explicit QueuePipeline(ClContext& cl) : DevicePipeline(cl) {}
    ~QueuePipeline() override;
    const char* name() const override { return "queue"; }
    const QueueStats& queueStats() const { return queue_; }

    // Ray slots a frame uses: --pool, else a size chosen from the device (and --memory-budget);
    // never fewer than C^B, the most rays one path can hold at once. Throws rt::Error when
    // --pool is below that.
    static size_t poolSize(const DeviceInfo& device, int branching, int bounces,
                           const RenderOptions& options, size_t nodeBytes = sizeof(dev::Node));
    // Device bytes per pool slot: ray fields, staging, node, queues (independent of B). A pool
    // takes pool * bytesPerRay + 4 + RT_Q_WORDS * 4 bytes (QueueStats::poolBytes).
    // nodeBytes: a Node's size in the scene's programs (dev::nodeBytes of its light count).
    static size_t bytesPerRay(int branching, QueueShadeMode shade = QueueShadeMode::Class,
                              size_t nodeBytes = sizeof(dev::Node));
    // The shade queues a mode keeps, each as long as the pool: the classes', the pattern mode's
    // (the procedural one split), or sort's (misses, hits, hits sorted).
    static int shadeQueues(QueueShadeMode shade);
    // A ray's record in the pool: origin, direction, weight (3 floats each), pixel and meta.
    static constexpr size_t kRayRecordBytes = 3 * 12 + 2 * 4;
    // Work-group size of the scan (and the most any queue kernel uses): a power of two, the
    // device's own choice, or --queue-group where given (refused by name when it is not a power
    // of two or passes the device's limit).
    static int groupSize(const DeviceInfo& device);
    static int groupSize(const DeviceInfo& device, const RenderOptions& options);
    // Whether the extend and shadow stages trace packets of kPacket queue entries per work-item
    // (--queue-packets; wavefront/queue/queue_packet.cl), or why not: "" when they do. Throws
    // rt::Error, one line naming the flag, when `on` is asked for and cannot be had.
    static std::string packetRefusal(const DeviceInfo& device, const Scene& scene,
                                     const RenderOptions& options);
    static bool usesPackets(const DeviceInfo& device, const Scene& scene,
                            const RenderOptions& options);
    static constexpr int kPacket = 16;
    // Tests only: drop the hit of this lane of every packet (the test that packets give the same
    // bits must see it); -1: none.
    void setDropLaneForTest(int lane) { dropLane_ = lane; }
    // Tests only: price every launch at its items times `ms` instead of its profiling event, so
    // that --max-launch-ms splits the stages the same way on any device (0: real timings).
    void setFakeItemMsForTest(double ms) { fakeItemMs_ = ms; }
    // Tests only: the material id of each entry of the last bounce's sorted hit queue
    // (--queue-shade sort), in queue order, read from the device after a frame.
    std::vector<int> sortedMaterialsForTest();

  private:
    Image renderFrame(const Scene& scene, const RenderOptions& options) override;
    void prepareBuffers(size_t pool, int branching, size_t pixels, int queues);
    void releaseBuffers();

    QueueBuffers buf_;
    size_t nodeBytes_ = sizeof(dev::Node);  // a hit record in the current scene's programs
    DeviceBuffer rayTally_, sortKeys_;
    QueueKernels kernels_;
    QueueStats queue_;
    // --max-launch-ms: the rays a bounce may admit and what an item of each stage costs (for
    // the pieces a launch is split into), learned by the frames of this workload so far.
    std::string learnedKey_;
    size_t learnedLimit_ = 0;
    StageCosts stageCosts_;
    double fakeItemMs_ = 0;
    int dropLane_ = -1;
};

}  // namespace rt
