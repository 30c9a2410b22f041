// rtlab — the queue wavefront's option declarations and their typed read-back (queue_options.h).
#include "wavefront/queue/queue_options.h"

namespace rt {

namespace {

constexpr long long kMaxPool = 1ll << 26;  // keeps every index of C * pool in an int

const PipelineOption& launchOption() {
    static const PipelineOption o{
        .name = "queue-launch",
        .type = PipelineOption::Type::Choice,
        .help =
            "Queue pipeline: how launches are sized: readback (the host reads each "
            "bounce's counts) or device (all bounces enqueued at once, counts read on the "
            "device) [readback]",
        .defaultValue = "readback",
        .choices = {"readback", "device"},  // QueueLaunchMode's order
        .sweepKey = "queue-launch",
        .cellTag = "Q",
        .label = "{}-sized",
    };
    return o;
}

const PipelineOption& poolOption() {
    static const PipelineOption o{
        .name = "pool",
        .type = PipelineOption::Type::Integer,
        .help =
            "Queue pipeline: ray slots in the pool, 1..67108864 (memory does not grow with "
            "--bounces) [from the device: 2M on GPUs, 64K on CPUs]",
        .defaultValue = 0ll,  // chosen from the device
        .min = 1,
        .max = kMaxPool,
        .sweepKey = "pool",
        .cellTag = "P",
        .label = "pool {}",
    };
    return o;
}

const PipelineOption& packetsOption() {
    static const PipelineOption o{
        .name = "queue-packets",
        .type = PipelineOption::Type::Choice,
        .help =
            "Queue pipeline: trace the extend and shadow queues 16 rays per work-item "
            "through the wide BVH: auto (on a CPU device with --accel wide), on or off "
            "[auto]",
        .defaultValue = "auto",
        .choices = {"auto", "on", "off"},  // QueuePacketMode's order
        .sweepKey = "queue-packets",
        .cellTag = "K",
        .label = "packets {}",
    };
    return o;
}

const PipelineOption& shadeOption() {
    static const PipelineOption o{
        .name = "queue-shade",
        .type = PipelineOption::Type::Choice,
        .help =
            "Queue pipeline: which rays share a shade launch: class (one queue per material "
            "class), pattern (one queue and kernel per procedural pattern too) or sort (every "
            "hit in one launch, sorted by material) [class]",
        .defaultValue = "class",
        .choices = {"class", "pattern", "sort"},  // QueueShadeMode's order
        .sweepKey = "queue-shade",
        .cellTag = "S",
        .label = "shade {}",
    };
    return o;
}

const PipelineOption& groupOption() {
    static const PipelineOption o{
        .name = "queue-group",
        .type = PipelineOption::Type::Integer,
        .help =
            "Queue pipeline: work-items per work-group of its kernels, a power of two up to the "
            "device's limit [from the device: 256 on GPUs, 64 on CPUs]",
        .defaultValue = 0ll,  // chosen from the device
        .min = 1,
        .max = 1024,
        .sweepKey = "queue-group",
        .cellTag = "I",
        .label = "groups of {}",
    };
    return o;
}

const PipelineOption& localPadOption() {
    static const PipelineOption o{
        .name = "queue-local-pad",
        .type = PipelineOption::Type::Integer,
        .help =
            "Queue pipeline, a diagnostic: bytes of local memory that hold nothing, added to "
            "each work-group of the extend, shadow and shade kernels, so that fewer groups fit "
            "a compute unit at once (what occupancy is worth to them); the image is the same "
            "[0]",
        .defaultValue = 0ll,
        .min = 0,
        .max = 1 << 20,
        .sweepKey = "queue-local-pad",
        .cellTag = "Z",
        .label = "with {} B of local pad",
    };
    return o;
}

}  // namespace

std::vector<PipelineOption> queueOptions() {
    return {launchOption(), poolOption(),  packetsOption(),
            shadeOption(),  groupOption(), localPadOption()};
}

std::vector<PipelineVariant> queueVariants() {
    // Small groups with their local memory padded, as bench/sweeps/queue-occupancy runs them
    // (16 KiB, which every OpenCL device has twice over), beside the defaults.
    PipelineVariant padded{"padded", {}};
    groupOption().set(padded.values, 64ll);
    localPadOption().set(padded.values, 16384ll);
    return {PipelineVariant{"", {}}, padded};
}

int queueGroup(const RenderOptions& o) { return int(groupOption().integer(o.pipelineOptions)); }

void setQueueGroup(RenderOptions& o, int items) {
    if (items == 0)
        o.pipelineOptions.reset(groupOption().name);
    else
        groupOption().set(o.pipelineOptions, (long long)(items));
}

size_t queueLocalPad(const RenderOptions& o) {
    return size_t(localPadOption().integer(o.pipelineOptions));
}

void setQueueLocalPad(RenderOptions& o, size_t bytes) {
    localPadOption().set(o.pipelineOptions, (long long)(bytes));
}

QueueLaunchMode queueLaunch(const RenderOptions& o) {
    return QueueLaunchMode(launchOption().index(o.pipelineOptions));
}

void setQueueLaunch(RenderOptions& o, QueueLaunchMode mode) {
    launchOption().set(o.pipelineOptions, queueLaunchName(mode));
}

size_t queuePool(const RenderOptions& o) { return size_t(poolOption().integer(o.pipelineOptions)); }

void setQueuePool(RenderOptions& o, size_t rays) {
    if (rays == 0)
        o.pipelineOptions.reset(poolOption().name);
    else
        poolOption().set(o.pipelineOptions, (long long)(rays));
}

QueuePacketMode queuePackets(const RenderOptions& o) {
    return QueuePacketMode(packetsOption().index(o.pipelineOptions));
}

void setQueuePackets(RenderOptions& o, QueuePacketMode mode) {
    packetsOption().set(o.pipelineOptions, queuePacketsName(mode));
}

QueueLaunchMode parseQueueLaunch(const std::string& name) {
    return QueueLaunchMode(launchOption().indexOf(name));
}

const char* queueLaunchName(QueueLaunchMode mode) {
    return launchOption().choices.at(size_t(mode)).c_str();
}

QueuePacketMode parseQueuePackets(const std::string& name) {
    return QueuePacketMode(packetsOption().indexOf(name));
}

const char* queuePacketsName(QueuePacketMode mode) {
    return packetsOption().choices.at(size_t(mode)).c_str();
}

QueueShadeMode queueShade(const RenderOptions& o) {
    return QueueShadeMode(shadeOption().index(o.pipelineOptions));
}

void setQueueShade(RenderOptions& o, QueueShadeMode mode) {
    shadeOption().set(o.pipelineOptions, queueShadeName(mode));
}

QueueShadeMode parseQueueShade(const std::string& name) {
    return QueueShadeMode(shadeOption().indexOf(name));
}

const char* queueShadeName(QueueShadeMode mode) {
    return shadeOption().choices.at(size_t(mode)).c_str();
}

}  // namespace rt
