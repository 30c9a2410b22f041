// rtlab — batches of given rays through rtlab's scene queries on an OpenCL device:
// the kernels of core/cl/trace_rays.cl bound to one --accel structure, one ray per work-item
// (Rays_Closest / Rays_Occluded, the pipelines' Scene_Intersect and Scene_Occluded) or, on the
// wide BVH, a packet of 8 or 16 rays per work-item (Rays_ClosestPacket / Rays_OccludedPacket,
// core/cl/accel_wide_packet.cl, for CPU devices). rtlab-trace-bench times them against Embree;
// tests/packet_trace_test.cpp holds the packets to the single rays' results.
#pragma once

#include <string>
#include <vector>

#include "bench/embree_peer.h"
#include "core/pipeline.h"

namespace rt {

class BatchTracer {
  public:
    // packet 0: one ray per work-item; 8 or 16: the packet kernels (accel must be Wide, the
    // scene triangles only), else rt::Error naming the --accels entry `label`.
    BatchTracer(ClContext& cl, const Scene& scene, const RenderOptions& options, int packet,
                const std::string& label);

    // t of each ray's closest hit below its tMax, -1 on a miss. Returns wall seconds from the
    // launch to the end of the kernel (not the transfers); lastDeviceS() is the kernel's own
    // (profiling event). local 0 lets the driver pick the work-group size.
    double closest(const cl::Buffer& rays, const cl::Buffer& t, size_t count, size_t local = 0);
    // 1 where something lies between a ray's origin and its tMax, else 0.
    double occluded(const cl::Buffer& rays, const cl::Buffer& blocked, size_t count,
                    size_t local = 0);
    double lastDeviceS() const { return lastDeviceS_; }
    int packet() const { return packet_; }
    const DeviceScene& device() const { return device_; }
    const cl::Program& program() const { return program_; }
    // Its build log (ClContext::lastBuildLog()), where NVIDIA's registers are read.
    const std::string& buildLog() const { return buildLog_; }

    // Upload, trace and read back in one call (tests).
    std::vector<float> closest(const std::vector<BatchRay>& rays);
    std::vector<int> occluded(const std::vector<BatchRay>& rays);

  private:
    // `output` names the kernel's result argument ("t" or "occluded").
    double run(Kernel& kernel, const cl::Buffer& in, const char* output, const cl::Buffer& out,
               size_t count, size_t local);
    ClContext& cl_;
    int packet_;
    DeviceScene device_;
    cl::Program program_;
    std::string buildLog_;
    Kernel closest_, occluded_;
    double lastDeviceS_ = 0;
};

// A read-only device copy of the rays (32 bytes for an empty batch, so that it still binds).
cl::Buffer uploadRays(ClContext& cl, const std::vector<BatchRay>& rays);

}  // namespace rt
