// rtlab — the bounce loop's scratch (bounce.h).
#include "wavefront/bounce/bounce.h"

#include <algorithm>
#include <limits>
#include <string>

#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/scene.h"
#include "wavefront/bounce/bounce_state.h"

namespace rt {

void BounceScratch::bind(ClContext& cl, Kernel& kernel, FrameStats& stats, const Scene& scene,
                         const RenderOptions& o, size_t groups, size_t lanes, bool staged) {
    // Per work-group, as bounce.cl's Persistent_RenderBounce indexes it: two lists as long as the
    // widest bounce a batch can reach (every ray of the last one glass), a tree of terms a pixel,
    // and, staged, a hit and an index for each ray of one such list.
    const size_t batch = kBounceBatchPerLane * lanes;
    const int branching = scene.branching();
    const size_t widest = batch << (o.bounces * (branching - 1));
    const size_t rayBytes = groups * 2 * widest * sizeof(dev::BounceRay);
    const size_t termBytes =
        groups * batch * size_t(treeNodeCount(branching, o.bounces)) * sizeof(dev::BounceTerm);
    const size_t hitBytes = staged ? groups * widest * dev::bounceHitBytes(scene.lights.size()) : 0;
    const size_t orderBytes = staged ? groups * widest * sizeof(cl_int) : 0;
    const size_t total = rayBytes + termBytes + hitBytes + orderBytes;
    const DeviceInfo& dev = cl.device();
    const auto mib = [](size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; };
    // The kernel indexes a list with an int.
    if (std::max({rayBytes, termBytes, hitBytes}) > dev.maxAlloc || total > dev.globalMem / 2 ||
        widest > size_t(std::numeric_limits<cl_int>::max()))
        throw Error("the bounce loop: " + std::to_string(groups) +
                        " work-groups tracing batches of " + std::to_string(batch) +
                        " pixels bounce by bounce at --bounces " + std::to_string(o.bounces) +
                        " need " + mib(rayBytes) + " of rays, " + mib(termBytes) + " of terms" +
                        (staged ? " and " + mib(hitBytes + orderBytes) + " of staged hits"
                                : std::string()) +
                        ", and " + dev.name + " allocates at most " + mib(dev.maxAlloc) +
                        " a buffer and half its " + mib(dev.globalMem) +
                        " in all here; lower --persistent-lanes, --persistent-groups or --bounces",
                    FailureKind::InvalidOption);
    try {
        rays_.ensure(cl, rayBytes, "the bounce loop's ray lists");
        terms_.ensure(cl, termBytes, "the bounce loop's trees of terms");
        if (staged) {
            hits_.ensure(cl, hitBytes, "the bounce loop's staged hits");
            order_.ensure(cl, orderBytes, "the bounce loop's hit indices");
        }
    } catch (const cl::Error& e) {
        throwClError(e, "preparing the bounce loop's scratch");
    }
    stats.addBuffer("bounce rays", rayBytes);
    stats.addBuffer("bounce terms", termBytes);
    kernel.set("rays", rays_.get()).set("terms", terms_.get());
    kernel.set("batch", cl_int(batch)).set("widest", cl_int(widest));
    if (staged) {
        stats.addBuffer("bounce hits", hitBytes);
        stats.addBuffer("bounce order", orderBytes);
        kernel.set("hits", hits_.get()).set("order", order_.get());
    }
}

void BounceScratch::reset() {
    for (DeviceBuffer* scratch : {&rays_, &terms_, &hits_, &order_}) scratch->reset();
}

}  // namespace rt
