// rtlab — Embree 3 as a peer of rtlab's traversal (see embree_peer.h). Rays go
// through the stream API (rtcIntersect1M / rtcOccluded1M, coherent context) in chunks that
// the threads take from a shared counter, so that every core works until the batch is done.
#include "bench/embree_peer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "core/error.h"

namespace rt {
namespace {

constexpr size_t kChunk = 256;  // rays per stream call: a few 8x8 tiles of the frame

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Runs fn(begin, end) over [0, n) in chunks on `threads` threads; returns wall seconds.
template <class Fn>
double parallelChunks(size_t n, unsigned threads, Fn&& fn) {
    std::atomic<size_t> next{0};
    auto work = [&] {
        for (;;) {
            size_t b = next.fetch_add(kChunk);
            if (b >= n) return;
            fn(b, std::min(n, b + kChunk));
        }
    };
    auto t0 = Clock::now();
    std::vector<std::thread> pool;
    for (unsigned i = 1; i < threads; ++i) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
    return secondsSince(t0);
}

void setRay(RTCRay& r, const BatchRay& b) {
    r.org_x = b.ox, r.org_y = b.oy, r.org_z = b.oz;
    r.dir_x = b.dx, r.dir_y = b.dy, r.dir_z = b.dz;
    r.tnear = 0.f;
    r.tfar = b.tMax;
    r.time = 0.f;
    r.mask = ~0u;
    r.id = 0;
    r.flags = 0;
}

}  // namespace

bool EmbreePeer::available() { return true; }

EmbreePeer::EmbreePeer(const Scene& scene, unsigned threads) : threads_(std::max(1u, threads)) {
    if (scene.triangles.empty()) throw Error("the Embree peer needs a scene with triangles");
    std::string config = "threads=" + std::to_string(threads_);
    RTCDevice device = rtcNewDevice(config.c_str());
    if (!device) throw Error("Embree: rtcNewDevice failed (" + config + ")");
    device_ = device;
    auto t0 = Clock::now();
    RTCScene sc = rtcNewScene(device);
    scene_ = sc;
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    size_t n = scene.triangles.size();
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * n));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    if (!v || !idx) throw Error("Embree: out of memory for " + std::to_string(n) + " triangles");
    for (size_t i = 0; i < n; ++i) {
        const dev::Triangle& t = scene.triangles[i];
        for (int k = 0; k < 3; ++k) {
            const dev::Float3& p = k == 0 ? t.v0 : k == 1 ? t.v1 : t.v2;
            v[9 * i + 3 * k] = p.x, v[9 * i + 3 * k + 1] = p.y, v[9 * i + 3 * k + 2] = p.z;
            idx[3 * i + k] = unsigned(3 * i + k);
        }
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(sc, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(sc);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw Error("Embree: the scene build failed");
    buildMs_ = 1e3 * secondsSince(t0);
}

EmbreePeer::~EmbreePeer() {
    if (scene_) rtcReleaseScene(static_cast<RTCScene>(scene_));
    if (device_) rtcReleaseDevice(static_cast<RTCDevice>(device_));
}

std::string EmbreePeer::version() const {
    RTCDevice d = static_cast<RTCDevice>(device_);
    return std::to_string(rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_VERSION_MAJOR)) + "." +
           std::to_string(rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_VERSION_MINOR)) + "." +
           std::to_string(rtcGetDeviceProperty(d, RTC_DEVICE_PROPERTY_VERSION_PATCH));
}

double EmbreePeer::intersect(const std::vector<BatchRay>& rays, std::vector<float>& t,
                             std::vector<dev::Float3>& normal) const {
    RTCScene sc = static_cast<RTCScene>(scene_);
    t.resize(rays.size());
    normal.resize(rays.size());
    return parallelChunks(rays.size(), threads_, [&](size_t b, size_t e) {
        RTCRayHit batch[kChunk];
        for (size_t i = b; i < e; ++i) {
            setRay(batch[i - b].ray, rays[i]);
            batch[i - b].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        }
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        rtcIntersect1M(sc, &ctx, batch, unsigned(e - b), sizeof(RTCRayHit));
        for (size_t i = b; i < e; ++i) {
            const RTCRayHit& h = batch[i - b];
            bool hit = h.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            t[i] = hit ? h.ray.tfar : -1.f;
            normal[i] = {h.hit.Ng_x, h.hit.Ng_y, h.hit.Ng_z};
        }
    });
}

double EmbreePeer::occluded(const std::vector<BatchRay>& rays, std::vector<int>& blocked) const {
    RTCScene sc = static_cast<RTCScene>(scene_);
    blocked.resize(rays.size());
    return parallelChunks(rays.size(), threads_, [&](size_t b, size_t e) {
        RTCRay batch[kChunk];
        for (size_t i = b; i < e; ++i) setRay(batch[i - b], rays[i]);
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        rtcOccluded1M(sc, &ctx, batch, unsigned(e - b), sizeof(RTCRay));
        // Embree marks a blocked ray by setting tfar to -inf.
        for (size_t i = b; i < e; ++i) blocked[i] = batch[i - b].tfar < 0.f ? 1 : 0;
    });
}

}  // namespace rt
