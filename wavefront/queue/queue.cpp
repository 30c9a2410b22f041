// rtlab — the queue wavefront's frame loop: per AA sample, bounce after bounce over the pool until
// every pixel's path has ended. Two ways to size the launches (--queue-launch):
//  - readback (default): one read-back per bounce; the host reads the counters after the prefix
//    sum (children spawned) and sizes the next bounce, and its refill of camera rays, with them;
//  - device: no read-back until the frame ends. The pixels go through the pool in waves; each
//    wave's B + 1 bounces are enqueued at once over a bound the host knows (min(pool, C x the
//    last bound)), and every kernel reads its real length from the counters (Queue_Length).
// Either way the stage kernels within a bounce are launched over the queue's upper bound and read
// their exact length from the device, so a bounce costs at most one host round trip.
#include "wavefront/queue/queue.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <tuple>

#include "core/error.h"
#include "core/pipeline_registry.h"
#include "wavefront/queue/queue_frame.h"
#include "wavefront/queue/queue_layout.h"
#include "wavefront/queue/queue_split.h"

namespace rt {

using namespace queue_frame;  // QueueFrame, QueuePass and their helpers (queue_frame.h)

Image QueuePipeline::renderFrame(const Scene& scene, const RenderOptions& o) {
    if (o.adaptiveAa && o.aa > 1)
        throw Error("--adaptive is not supported by the queue pipeline (use --pipeline mega)",
                    FailureKind::InvalidOption);
    const bool onDevice = queueLaunch(o) == QueueLaunchMode::Device;
    if (onDevice && o.maxLaunchMs > 0)
        throw Error(
            "--queue-launch device does not go with --max-launch-ms: its admission is "
            "learned from each bounce's time, which needs --queue-launch readback",
            FailureKind::InvalidOption);
    queue_ = {};
    const int C = scene.branching();
    const DeviceInfo& dev = cl_.device();
    if (const size_t nodeBytes = dev::nodeBytes(scene.lights.size()); nodeBytes != nodeBytes_) {
        releaseBuffers();  // the hit records are sized by it
        nodeBytes_ = nodeBytes;
    }
    size_t pool = poolSize(dev, C, o.bounces, o, nodeBytes_);
    int group = groupSize(dev, o);
    if (const size_t pad = queueLocalPad(o); pad + kExtendLocalBytes > dev.localMem)
        throw Error("--queue-local-pad " + std::to_string(pad) + ": with the extend kernel's own " +
                        std::to_string(kExtendLocalBytes) + " bytes it passes the " +
                        std::to_string(dev.localMem) +
                        " bytes of local memory a work-group has on " + dev.name,
                    FailureKind::InvalidOption);
    const bool packets = usesPackets(dev, scene, o);
    const std::vector<std::string> defines = programDefines(scene, o, group, packets, dropLane_);
    cl::Program program = this->program("queue.cl", defines);
    DeviceScene& deviceScene = this->deviceScene(scene, o.accel);
    size_t pixels = size_t(o.width) * size_t(o.height);
    auto hint = [&] {
        return "the queue pipeline's pool of " + std::to_string(pool) + " rays takes " +
               std::to_string(pool * bytesPerRay(C, queueShade(o), nodeBytes_) >> 20) +
               " MiB; lower it with --pool";
    };
    const QueueShadeMode shade = queueShade(o);
    try {
        prepareBuffers(pool, C, pixels, shadeQueues(shade));
        rayTally_.ensure(cl_, (o.countRays ? pixels + 1 : 1) * RT_RAY_TYPES * sizeof(cl_uint),
                         "the queue pipeline's per-pixel ray counts");
        buf_.rayTally = rayTally_.get();
        sortKeys_.ensure(cl_, std::max<size_t>(scene.materials.size(), 1) * 4,
                         "the queue pipeline's per-material sort keys");
        buf_.sortKeys = sortKeys_.get();
    } catch (const cl::Error& e) {
        throwClError(e, "preparing queue-pipeline buffers", hint());
    }
    queue_.poolRays = pool;
    queue_.poolBytes = buf_.poolBytes;
    queue_.packets = packets;
    stats_.privateBytes = 0;  // a work-item keeps one ray; the state lives in the pool

    dev::RenderSettings settings = makeSettings(scene, o);
    Image out(o.width, o.height);
    if (kernels_.program != program()) kernels_ = QueueKernels{program(), {}, {}};
    // What --max-launch-ms learned (the admission limit, each stage's cost per item) is kept
    // while the workload stays the same.
    std::string key = std::to_string(o.maxLaunchMs) + " " + std::to_string(o.width) + "x" +
                      std::to_string(o.height) + " B" + std::to_string(o.bounces) + " s" +
                      std::to_string(o.shadowSamples) + " " + scene.source.string();
    for (const std::string& d : defines) key += " " + d;
    key += std::string(" ") + queueLaunchName(queueLaunch(o));
    if (key != learnedKey_) {
        learnedLimit_ = 0;
        stageCosts_.clear();
    }
    QueueFrame frame(cl_, program, deviceScene, group, kernels_, stageCosts_,
                     onDevice ? 0.0 : o.maxLaunchMs, fakeItemMs_, packets);
    try {
        startRayCount(o);
        if (o.countRays)
            cl_.queue().enqueueFillBuffer(rayTally_.get(), cl_uint(0), 0, rayTally_.bytes());
        cl_.queue().enqueueFillBuffer(buf_.counters, cl_int(0), 0, RT_Q_WORDS * 4);
        Kernel& resolve = frame.kernel("Queue_Resolve");
        resolve.set("sums", buf_.sums)
            .set("image", buf_.image)
            .set("pixels", cl_int(pixels))
            .set("samples", cl_int(o.aa * o.aa));
        QueuePass pass(cl_, frame, buf_, o, queue_, learnedLimit_);
        // Progress in pixels started x AA samples, over the row window.
        const size_t first = pass.firstPixel(), window = pass.endPixel() - first;
        const long long total = (long long)(window)*o.aa * o.aa;
        for (int s = 0; s < o.aa * o.aa; ++s) {
            settings.sampleIndex = s;
            pass.run(settings, shadeLaunches(scene, shade), int(scene.materials.size()),
                     [&](size_t started) {
                         reportProgress((long long)(s) * (long long)(window) + (long long)(started),
                                        total);
                     });
            resolve.set("sample", cl_int(s));
            frame.launch("Queue_Resolve", pixels);
        }
        learnedKey_ = key;
        learnedLimit_ = pass.limit();
        cl_.queue().enqueueReadBuffer(buf_.image, CL_TRUE, first * 12, window * 12,
                                      out.rgb.data() + first * 3);
        std::vector<cl_int> words(RT_Q_WORDS);
        cl_.queue().enqueueReadBuffer(buf_.counters, CL_TRUE, 0, words.size() * 4, words.data());
        for (int d = 0; d <= o.bounces; ++d) {
            std::array<long long, RT_Q_CLASSES> row{};
            for (int c = 0; c < RT_Q_CLASSES; ++c)
                row[c] = words[RT_Q_HISTOGRAM + d * RT_Q_CLASSES + c];
            queue_.queueLengths.push_back(row);
        }
        finishRayCount(o);
        if (o.countRays) {
            // Every path has ended and added its rays; the tally's first words are the rays
            // of the cut attempts (queue.cl).
            cl_uint retraced[RT_RAY_TYPES];
            cl_.queue().enqueueReadBuffer(rayTally_.get(), CL_TRUE, 0, sizeof retraced, retraced);
            for (int t = 0; t < RT_RAY_TYPES; ++t) queue_.retracedRays[t] = retraced[t];
        }
        if (o.maxLaunchMs > 0) frame.learn(nullptr);  // the last bounce's and resolve's
        queue_.shadeMs = 0;
        for (const QueueLaunch& l : frame.launches()) {
            stats_.addKernel(stageName(l.kernel), frame.ms(l));
            if (isShadeStage(l.kernel)) queue_.shadeMs += frame.ms(l);
        }
        stats_.launches = int(frame.launches().size());
        std::tie(queue_.spanMs, queue_.idleMs) = spanAndIdleMs(frame.launches());
        queue_.fellBack = words[RT_Q_OVERFLOW] != 0;
    } catch (const cl::Error& e) {
        throwClError(e, "queue-pipeline frame on " + dev.name, hint());
    }
    if (queue_.fellBack) {
        // A bounce's children outgrew the pool, and device sizing does not cut paths: this
        // frame's image is incomplete. Render it again with read-backs, which cut and restart.
        RenderOptions again = o;
        setQueueLaunch(again, QueueLaunchMode::Readback);
        stats_ = {};
        Image image = renderFrame(scene, again);
        queue_.fellBack = true;
        stats_.extras["queue_launch"] = "device, fell back to readback";
        return image;
    }
    stats_.addBuffer("pool", queue_.poolBytes);
    stats_.addBuffer("image", buf_.imageBytes);
    stats_.extras["pool_rays"] = queue_.poolRays;  // its bytes: buffers["pool"]
    // What each extended ray moves through global memory at the least, for the memory floor of
    // the result READMEs (tools/rtlab_report/readme_floor.py): its ray record and its hit record.
    stats_.extras["ray_record_bytes"] = kRayRecordBytes;
    stats_.extras["hit_record_bytes"] = nodeBytes_;
    stats_.extras["bounces_run"] = queue_.iterations;
    stats_.extras["restarted_paths"] = queue_.restartedPaths;
    if (o.countRays) stats_.extras["retraced_rays"] = queue_.retracedRays;  // by RT_RAY_* type
    stats_.extras["queue_lengths"] = queue_.queueLengths;  // [depth][miss, diffuse, mirror, glass]
    stats_.extras["queue_launch"] = queueLaunchName(queueLaunch(o));
    stats_.extras["queue_packets"] = packets ? kPacket : 0;  // rays per extend/shadow work-item
    stats_.extras["queue_shade"] = queueShadeName(shade);
    // The shade stage, all its kernels (and the sort's) summed: what the modes differ in.
    stats_.extras["shade_ms"] = queue_.shadeMs;
    if (!onDevice) stats_.extras["shade_queue_rays"] = queue_.shadeQueueRays;
    stats_.extras["readbacks"] = queue_.readbacks;
    stats_.extras["span_ms"] = queue_.spanMs;
    stats_.extras["idle_ms"] = queue_.idleMs;
    return out;
}

std::vector<int> QueuePipeline::sortedMaterialsForTest() {
    cl::CommandQueue& q = cl_.queue();
    cl_int hits = 0;
    q.enqueueReadBuffer(buf_.counters, CL_TRUE, (RT_Q_COUNT + RT_Q_HITS) * 4, 4, &hits);
    std::vector<cl_int> order(size_t(std::max(hits, 0)));
    if (order.empty()) return {};
    q.enqueueReadBuffer(buf_.shadeQueues, CL_TRUE, RT_Q_SORTED * buf_.pool * 4, order.size() * 4,
                        order.data());
    std::vector<unsigned char> nodes(buf_.pool * nodeBytes_);  // records of nodeBytes_ each
    q.enqueueReadBuffer(buf_.nodes, CL_TRUE, 0, nodes.size(), nodes.data());
    std::vector<int> materials;
    for (cl_int i : order) {
        uint16_t material;
        std::memcpy(&material, &nodes.at(size_t(i) * nodeBytes_ + offsetof(dev::Node, material)),
                    sizeof material);
        materials.push_back(material);
    }
    return materials;
}

std::string QueuePipeline::packetRefusal(const DeviceInfo& device, const Scene& scene,
                                         const RenderOptions& o) {
    if (o.accel != RenderOptions::Accel::Wide)
        return "packets traverse the wide BVH only (use --accel wide)";
    if (scene.triangles.empty()) return "packets trace triangles, and the scene has none";
    if (device.type != "CPU")
        return "packets are for CPU devices, and " + device.name + " is a " + device.type;
    return "";
}

bool QueuePipeline::usesPackets(const DeviceInfo& device, const Scene& scene,
                                const RenderOptions& o) {
    const QueuePacketMode mode = queuePackets(o);
    if (mode == QueuePacketMode::Off) return false;
    std::string why = packetRefusal(device, scene, o);
    if (mode == QueuePacketMode::On) {
        if (!why.empty()) throw Error("--queue-packets on: " + why, FailureKind::InvalidOption);
        return true;
    }
    // auto: spheres sit in the BVH's leaves too, but a packet tests them ray by ray; only
    // triangle scenes (planes are tested per ray before the BVH either way) are sure to gain.
    return why.empty() && scene.spheres.empty();
}

void registerQueueWavefront(PipelineRegistry& registry) {
    PipelineInfo p;
    p.name = "queue";
    p.title = "wavefront (queues of live rays)";
    p.family = "wavefront";
    p.description =
        "a pool of live rays in SoA buffers; generate, extend, shadow and per-material "
        "shade kernels over compacted queues (--pool N)";
    p.supports = {.adaptiveAa = false, .tiling = false, .rowWindow = true};
    p.options = queueOptions();
    // Device-sized launches learn no admission limit (that takes a read-back per bounce): the
    // command line's default launch cap gives way to them; a cap asked for is refused in render().
    p.settleDefaults = [](RenderOptions& o, bool launchCapGiven) {
        if (queueLaunch(o) == QueueLaunchMode::Device && !launchCapGiven) o.maxLaunchMs = 0;
    };
    p.variants = queueVariants();
    p.make = [](ClContext* cl) { return std::make_unique<QueuePipeline>(*cl); };
    registry.add(std::move(p));
}

}  // namespace rt
