// rtlab — the queue wavefront's memory: how many ray slots the pool gets on a device, and the
// pool's buffers. Everything here scales with the pool (and the image), never with the bounce
// limit: a deeper tree only means more bounces through the same slots.
#include <algorithm>
#include <string>

#include "core/error.h"
#include "wavefront/queue/queue.h"
#include "wavefront/queue/queue_layout.h"

namespace rt {

namespace {
constexpr size_t kMaxPool = size_t(1) << 26;  // keeps every index of C * pool in an int
}  // namespace

int QueuePipeline::shadeQueues(QueueShadeMode shade) {
    switch (shade) {
        case QueueShadeMode::Pattern:
            return RT_Q_QUEUES;
        case QueueShadeMode::Sort:
            return RT_Q_SORTED + 1;
        case QueueShadeMode::Class:
            break;
    }
    return RT_Q_CLASSES;
}

size_t QueuePipeline::bytesPerRay(int branching, QueueShadeMode shade, size_t nodeBytes) {
    return kRayRecordBytes * size_t(1 + branching)  // the queue and its C staging slots
           + nodeBytes                              // extend's hit record, read by shade
           + 12                                     // contribution
           + 4 * 4                                  // children, offsets, block sums, retry
           + 4 * size_t(shadeQueues(shade) + 1);    // shade queues and shadow queue
}

int QueuePipeline::groupSize(const DeviceInfo& device) {
    // 256 on GPUs (8 warps); 64 on CPUs, where PoCL runs a group's items in one thread's loop.
    size_t want = device.isGpu() ? 256 : 64, g = 1;
    while (g * 2 <= want && g * 2 <= device.maxWorkGroup) g *= 2;
    return int(g);
}

int QueuePipeline::groupSize(const DeviceInfo& device, const RenderOptions& o) {
    const int asked = queueGroup(o);
    if (asked == 0) return groupSize(device);
    const std::string flag = "--queue-group " + std::to_string(asked);
    // The scans halve and double their strides over the whole group.
    if ((asked & (asked - 1)) != 0)
        throw Error(flag + ": must be a power of two", FailureKind::InvalidOption);
    if (size_t(asked) > device.maxWorkGroup)
        throw Error(flag + ": " + device.name + " runs at most " +
                        std::to_string(device.maxWorkGroup) + " work-items a group",
                    FailureKind::InvalidOption);
    return asked;
}

size_t QueuePipeline::poolSize(const DeviceInfo& device, int branching, int bounces,
                               const RenderOptions& o, size_t nodeBytes) {
    size_t widest = 1;  // C^B: a path's widest bounce (every ray spawns C children)
    for (int b = 0; b < bounces; ++b) widest *= size_t(branching);
    if (const size_t asked = queuePool(o)) {
        if (asked > kMaxPool)
            throw Error(
                "--pool " + std::to_string(asked) + ": must be in 1.." + std::to_string(kMaxPool),
                FailureKind::InvalidOption);
        if (asked < widest)
            throw Error("--pool " + std::to_string(asked) + ": one path of this scene (C = " +
                            std::to_string(branching) + ") can hold " + std::to_string(widest) +
                            " rays at once at --bounces " + std::to_string(bounces) +
                            "; use --pool " + std::to_string(widest) + " or more",
                        FailureKind::InvalidOption);
        return asked;
    }
    // About 2 M rays on a GPU (a 1080p frame's camera rays in one launch), 64 K on a CPU; then
    // halved until the pool fits a quarter of global memory, --memory-budget and the largest
    // single allocation (the staging origins, C x 12 B per slot).
    size_t pool = device.isGpu() ? size_t(1) << 21 : size_t(1) << 16;
    size_t budget = size_t(device.globalMem / 4);
    if (o.memoryBudget) budget = std::min(budget, o.memoryBudget);
    while (pool > 1024 && (pool * bytesPerRay(branching, queueShade(o), nodeBytes) > budget ||
                           pool * size_t(branching) * 12 > device.maxAlloc))
        pool /= 2;
    return std::max(pool, widest);
}

void QueuePipeline::releaseBuffers() {
    cl_.release(buf_.poolBytes + buf_.imageBytes);
    buf_ = QueueBuffers();
}

QueuePipeline::~QueuePipeline() { cl_.release(buf_.poolBytes + buf_.imageBytes); }

void QueuePipeline::prepareBuffers(size_t pool, int branching, size_t pixels, int queues) {
    if (buf_.pool == pool && buf_.branching == branching && buf_.pixels == pixels &&
        buf_.queues == queues)
        return;
    // Drop everything first: after a failed allocation no stale size names a buffer that is gone.
    releaseBuffers();
    QueueBuffers b;
    size_t tally = 0;
    auto make = [&](size_t bytes, const char* what) {
        cl::Buffer buffer = cl_.allocate(bytes, CL_MEM_READ_WRITE, what);
        tally += bytes;
        return buffer;
    };
    auto rays = [&](QueueBuffers::Rays& r, size_t n, const char* what) {
#define QUEUE_RAYS_F3(X, field, Field, member) r.field = make(n * RT_RAY_STATE_F3_BYTES, what);
#define QUEUE_RAYS_META(X, field, Field) r.field = make(n * RT_RAY_STATE_META_BYTES, what);
        RT_RAY_STATE(QUEUE_RAYS_F3, QUEUE_RAYS_META, _)
#undef QUEUE_RAYS_F3
#undef QUEUE_RAYS_META
        r.pixel = make(n * 4, what);
    };
    try {
        rays(b.rays, pool, "the queue pipeline's ray pool");
        rays(b.staging, pool * size_t(branching), "the queue pipeline's child staging area");
        b.nodes = make(pool * nodeBytes_, "the queue pipeline's hit records");
        b.contrib = make(pool * 12, "the queue pipeline's contributions");
        b.children = make(pool * 4, "the queue pipeline's child counts");
        b.offsets = make(pool * 4, "the queue pipeline's prefix sums");
        b.retry = make(pool * 4, "the queue pipeline's retry list");
        b.shadeQueues = make(pool * 4 * size_t(queues), "the queue pipeline's shade queues");
        b.shadowQueue = make(pool * 4, "the queue pipeline's shadow queue");
        b.blockSums = make((pool + 1) * 4, "the queue pipeline's block sums");
        b.counters = make(RT_Q_WORDS * 4, "the queue pipeline's counters");
        b.poolBytes = tally;
        tally = 0;
        b.sums = make(pixels * 12, "the queue pipeline's per-sample sums");
        b.image = make(pixels * 12, "the image buffer");
        b.imageBytes = tally;
    } catch (...) {
        cl_.release(b.poolBytes + tally);
        throw;
    }
    b.pool = pool;
    b.branching = branching;
    b.pixels = pixels;
    b.queues = queues;
    buf_ = std::move(b);
}

}  // namespace rt
