// rtlab — batches of given rays through rtlab's scene queries (see ray_batch.h).
#include "bench/ray_batch.h"

#include <algorithm>
#include <chrono>

#include "core/error.h"

namespace rt {
namespace {

// Why the packet kernels cannot trace this scene with these options, or "" when they can.
std::string packetRefusal(const Scene& s, const RenderOptions& o, int packet) {
    if (packet != 8 && packet != 16) return "packets hold 8 or 16 rays";
    if (o.accel != RenderOptions::Accel::Wide) return "packets traverse the wide BVH only";
    if (s.triangles.empty()) return "packets trace triangles, and the scene has none";
    if (!s.spheres.empty() || !s.planes.empty())
        return "packets trace triangles only, and the scene has spheres or planes";
    return "";
}

std::vector<std::string> programDefines(const Scene& s, const RenderOptions& o, int packet) {
    std::vector<std::string> d = featureDefines(s, o);
    if (packet) d.push_back("RT_PACKET=" + std::to_string(packet));
    return d;
}

}  // namespace

BatchTracer::BatchTracer(ClContext& cl, const Scene& scene, const RenderOptions& options,
                         int packet, const std::string& label)
    : cl_(cl), packet_(packet), device_(cl, scene, options.accel) {
    if (packet) {
        std::string why = packetRefusal(scene, options, packet);
        if (!why.empty()) throw Error("--accels " + label + ": " + why);
    }
    program_ = cl.program("trace_rays.cl", programDefines(scene, options, packet));
    buildLog_ = cl.lastBuildLog();
    closest_ = Kernel(program_, packet ? "Rays_ClosestPacket" : "Rays_Closest");
    occluded_ = Kernel(program_, packet ? "Rays_OccludedPacket" : "Rays_Occluded");
    device_.setArgs(closest_, makeSettings(scene, options));
    device_.setArgs(occluded_, makeSettings(scene, options));
}

double BatchTracer::run(Kernel& k, const cl::Buffer& in, const char* output, const cl::Buffer& out,
                        size_t n, size_t local) {
    k.set("rays", in).set(output, out).set("count", cl_int(n));
    auto t0 = std::chrono::steady_clock::now();
    // A packet kernel takes one work-item per packet. A local size must divide the global one:
    // round up; the kernels skip the padding.
    size_t items = packet_ ? (n + size_t(packet_) - 1) / size_t(packet_) : n;
    size_t global = local ? (items + local - 1) / local * local : items;
    cl::Event done;
    cl_.queue().enqueueNDRangeKernel(k.get(), cl::NullRange,
                                     cl::NDRange(std::max<size_t>(global, 1)),
                                     local ? cl::NDRange(local) : cl::NullRange, nullptr, &done);
    cl_.queue().finish();
    lastDeviceS_ = 1e-3 * eventMs(done);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double BatchTracer::closest(const cl::Buffer& rays, const cl::Buffer& t, size_t n, size_t local) {
    return run(closest_, rays, "t", t, n, local);
}

double BatchTracer::occluded(const cl::Buffer& rays, const cl::Buffer& blocked, size_t n,
                             size_t local) {
    return run(occluded_, rays, "occluded", blocked, n, local);
}

std::vector<float> BatchTracer::closest(const std::vector<BatchRay>& rays) {
    cl::Buffer in = uploadRays(cl_, rays);
    cl::Buffer out(cl_.context(), CL_MEM_WRITE_ONLY, std::max<size_t>(rays.size(), 4) * 4);
    closest(in, out, rays.size());
    std::vector<float> t(rays.size());
    if (!t.empty()) cl_.queue().enqueueReadBuffer(out, CL_TRUE, 0, t.size() * 4, t.data());
    return t;
}

std::vector<int> BatchTracer::occluded(const std::vector<BatchRay>& rays) {
    cl::Buffer in = uploadRays(cl_, rays);
    cl::Buffer out(cl_.context(), CL_MEM_WRITE_ONLY, std::max<size_t>(rays.size(), 4) * 4);
    occluded(in, out, rays.size());
    std::vector<int> b(rays.size());
    if (!b.empty()) cl_.queue().enqueueReadBuffer(out, CL_TRUE, 0, b.size() * 4, b.data());
    return b;
}

cl::Buffer uploadRays(ClContext& cl, const std::vector<BatchRay>& rays) {
    if (rays.empty()) return cl::Buffer(cl.context(), CL_MEM_READ_ONLY, 32);
    return cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                      rays.size() * sizeof(BatchRay), const_cast<BatchRay*>(rays.data()));
}

}  // namespace rt
