#include "core/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "core/accel.h"
#include "core/error.h"

namespace rt {

const char* rayTypeName(int type) {
    switch (type) {
        case RT_RAY_PRIMARY:
            return "primary";
        case RT_RAY_REFLECTION:
            return "reflection";
        case RT_RAY_REFRACTION:
            return "refraction";
        case RT_RAY_SHADOW:
            return "shadow";
    }
    return "?";
}

RenderOptions::Offset parseOffset(const std::string& name) {
    if (name == "fixed") return RenderOptions::Offset::Fixed;
    if (name == "scaled") return RenderOptions::Offset::Scaled;
    if (name == "bound") return RenderOptions::Offset::Bound;
    throw Error("--offset " + name + ": must be one of fixed, scaled, bound");
}

const char* offsetName(RenderOptions::Offset offset) {
    switch (offset) {
        case RenderOptions::Offset::Fixed:
            return "fixed";
        case RenderOptions::Offset::Scaled:
            return "scaled";
        case RenderOptions::Offset::Bound:
            return "bound";
    }
    return "?";
}

void FrameStats::addKernel(const std::string& name, double ms) {
    deviceMs += ms;
    longestLaunchMs = std::max(longestLaunchMs, ms);  // both pipelines add once per launch
    for (auto& [n, t] : kernelMs)
        if (n == name) {
            t += ms;
            return;
        }
    kernelMs.emplace_back(name, ms);
}

void FrameStats::addBuffer(const std::string& name, size_t bytes) {
    for (auto& [n, b] : buffers)
        if (n == name) {
            b = bytes;
            return;
        }
    buffers.emplace_back(name, bytes);
}

void checkOptions(const Scene& scene, const RenderOptions& o) {
    auto range = [](const char* flag, long long v, long long lo, long long hi) {
        if (v < lo || v > hi)
            throw Error(std::string(flag) + " " + std::to_string(v) + ": must be in " +
                            std::to_string(lo) + ".." + std::to_string(hi),
                        FailureKind::InvalidOption);
    };
    range("--size (width)", o.width, 1, 16384);
    range("--size (height)", o.height, 1, 16384);
    range("--bounces", o.bounces, 0, RT_MAX_BOUNCE_LIMIT);
    range("--shadow-samples", o.shadowSamples, 1, RT_MAX_SHADOW_SAMPLES);
    range("--aa", o.aa, 1, 16);
    if (o.rowBegin != 0 || o.rowEnd != 0) {  // set by front ends, never by a flag
        range("row window (first row)", o.rowBegin, 0, o.height - 1);
        range("row window (end row)", o.rowEnd, o.rowBegin + 1, o.height);
    }
    if (!(o.shadowStrength >= 0.f && o.shadowStrength <= 1.f))
        throw Error("shadow strength must be in [0, 1]", FailureKind::InvalidOption);
    if (scene.lights.size() > RT_MAX_LIGHTS)
        throw Error(scene.source.string() + ": at most " + std::to_string(RT_MAX_LIGHTS) +
                        " lights are supported",
                    FailureKind::InvalidOption);
}

size_t treePrivateBytes(int branching, int bounces, size_t nodeBytes) {
    // A node plus its colour (float3, 16 bytes in private memory) per tree slot.
    return size_t(treeNodeCount(branching, bounces)) * (nodeBytes + sizeof(cl_float3));
}

void checkPrivateTree(int branching, int bounces, const std::string& who, const std::string& hint,
                      size_t nodeBytes) {
    size_t need = treePrivateBytes(branching, bounces, nodeBytes);
    if (need <= kPrivateTreeLimit) return;
    int fits = bounces;
    while (fits > 0 && treePrivateBytes(branching, fits, nodeBytes) > kPrivateTreeLimit) --fits;
    std::string msg = "--bounces " + std::to_string(bounces) + ": the " + who + " keeps " +
                      std::to_string(treeNodeCount(branching, bounces)) + " ray-tree nodes (" +
                      std::to_string(need / 1024) +
                      " KiB) in private memory per work-item, over rtlab's " +
                      std::to_string(kPrivateTreeLimit / 1024) + " KiB cap; the highest bounce " +
                      "limit that fits is " + std::to_string(fits);
    throw Error(msg + hint, FailureKind::PrivateTree);
}

std::string treeNodesDefine(const Scene& scene, int bounces) {
    return "RT_TREE_NODES=" + std::to_string(treeNodeCount(scene.branching(), bounces));
}

std::vector<std::string> featureDefines(const Scene& scene, const RenderOptions& o) {
    std::vector<std::string> d;
    if (!scene.spheres.empty()) d.push_back("RT_HAS_SPHERES");
    if (!scene.planes.empty()) d.push_back("RT_HAS_PLANES");
    if (!scene.triangles.empty()) d.push_back("RT_HAS_TRIANGLES");
    if (scene.environment.cubemapSize > 0) d.push_back("RT_HAS_CUBEMAP");
    if (scene.hasProcedural()) d.push_back("RT_HAS_PROCEDURAL");
    // Only past 4 lights: the programs of every other scene stay as they were.
    if (const int lights = dev::nodeLights(scene.lights.size()); lights > 4)
        d.push_back("RT_NODE_LIGHTS=" + std::to_string(lights));
    int c = scene.branching();
    d.push_back("RT_BRANCH=" + std::to_string(c));
    if (o.countRays) d.push_back("RT_COUNT_RAYS");
    if (o.robustSphere) d.push_back("RT_ROBUST_SPHERE");
    if (o.watertight) d.push_back("RT_WATERTIGHT");
    if (o.offset == RenderOptions::Offset::Scaled) d.push_back("RT_SCALED_OFFSET");
    if (o.offset == RenderOptions::Offset::Bound) d.push_back("RT_BOUND_OFFSET");
    // The grid and the BVH hold spheres and triangles; bv bounds meshes. Without anything to
    // hold, the define is left out and the program loops over what there is.
    bool prims = !scene.spheres.empty() || !scene.triangles.empty();
    if (o.accel == RenderOptions::Accel::Bv && !scene.triangles.empty()) d.push_back("RT_ACCEL_BV");
    if (o.accel == RenderOptions::Accel::Grid && prims) d.push_back("RT_ACCEL_GRID");
    if (o.accel == RenderOptions::Accel::Bvh && prims) d.push_back("RT_ACCEL_BVH");
    if (o.accel == RenderOptions::Accel::Wide && prims) d.push_back("RT_ACCEL_WIDE");
    if (o.accel == RenderOptions::Accel::Cwbvh && prims) d.push_back("RT_ACCEL_CWBVH");
    return d;
}

dev::RenderSettings makeSettings(const Scene& scene, const RenderOptions& o) {
    dev::RenderSettings s;
    std::memset(&s, 0, sizeof s);
    s.width = o.width;
    s.height = o.height;
    s.bounces = o.bounces;
    s.shadowSamples = o.shadowSamples;
    s.aaSamples = o.aa;
    s.sphereCount = int(scene.spheres.size());
    s.planeCount = int(scene.planes.size());
    s.triangleCount = int(scene.triangles.size());
    s.meshCount = int(scene.meshes.size());
    s.lightCount = int(scene.lights.size());
    s.materialCount = int(scene.materials.size());
    s.shadowStrength = o.shadowStrength;
    s.cubemapSize = scene.environment.cubemapSize;
    s.skyZenith = scene.environment.zenith;
    s.skyHorizon = scene.environment.horizon;
    s.skyGround = scene.environment.ground;
    s.camera = scene.camera;
    return s;
}

template <typename T>
static cl::Buffer upload(ClContext& cl, const std::vector<T>& v, const char* what, size_t& total) {
    size_t bytes = v.size() * sizeof(T);
    cl::Buffer b = cl.allocate(bytes, CL_MEM_READ_ONLY, what);
    total += bytes;
    if (bytes) {
        try {
            cl.queue().enqueueWriteBuffer(b, CL_TRUE, 0, bytes, v.data());
        } catch (const cl::Error& e) {
            throwClError(e, std::string("uploading ") + what);
        }
    }
    return b;
}

DeviceScene::DeviceScene(ClContext& cl, const Scene& scene, RenderOptions::Accel a)
    : cl_(cl), source_(scene.id.value()), accel_(a) {
    AccelData accel = buildAccel(scene, a);
    stats_ = accel.stats;
    grid_ = accel.grid;
    try {
        spheres_ = upload(cl, accel.spheres, "the sphere buffer", bytes_);
        planes_ = upload(cl, scene.planes, "the plane buffer", bytes_);
        triangles_ = upload(cl, accel.triangles, "the triangle buffer", bytes_);
        meshes_ = upload(cl, accel.meshes, "the mesh buffer", bytes_);
        kdops_ = upload(cl, accel.kdops, "the bounding-volume buffer", bytes_);
        lights_ = upload(cl, scene.lights, "the light buffer", bytes_);
        materials_ = upload(cl, scene.materials, "the material buffer", bytes_);
        cubemap_ = upload(cl, scene.environment.cubemap, "the cubemap buffer", bytes_);
        // The wide nodes take the BVH's buffer, and the cwbvh's leaf entries the grid's: kernels
        // keep one signature for every mode.
        if (a == RenderOptions::Accel::Wide)
            bvh_ = upload(cl, accel.wide, "the BVH buffer", bytes_);
        else if (a == RenderOptions::Accel::Cwbvh)
            bvh_ = upload(cl, accel.cwbvh, "the BVH buffer", bytes_);
        else
            bvh_ = upload(cl, accel.bvh, "the BVH buffer", bytes_);
        if (a == RenderOptions::Accel::Cwbvh)
            cells_ = upload(cl, accel.cwbvhPrims, "the leaf-primitive buffer", bytes_);
        else
            cells_ = upload(cl, accel.cells, "the grid buffer", bytes_);
        rayCounts_ =
            cl.allocate(RT_COUNTERS * sizeof(cl_uint), CL_MEM_READ_WRITE, "the ray counters");
        bytes_ += RT_COUNTERS * sizeof(cl_uint);
    } catch (...) {
        cl_.release(bytes_);
        throw;
    }
}

DeviceScene::~DeviceScene() { cl_.release(bytes_); }

void DeviceScene::resetRayCounts(cl::CommandQueue& queue) const {
    queue.enqueueFillBuffer(rayCounts_, cl_uint(0), 0, RT_COUNTERS * sizeof(cl_uint));
}

RayCounts DeviceScene::readRayCounts(cl::CommandQueue& queue) const {
    cl_uint c[RT_RAY_TYPES];
    queue.enqueueReadBuffer(rayCounts_, CL_TRUE, 0, sizeof c, c);
    RayCounts out{};
    for (int i = 0; i < RT_RAY_TYPES; ++i) out[i] = c[i];
    return out;
}

WarpCounts DeviceScene::readWarpCounts(cl::CommandQueue& queue) const {
    // The warp counters and the phase clocks after them, in one read.
    cl_uint c[RT_COUNTERS - RT_RAY_TYPES];
    queue.enqueueReadBuffer(rayCounts_, CL_TRUE, RT_RAY_TYPES * sizeof(cl_uint), sizeof c, c);
    WarpCounts w;
    w.lanesActive = c[RT_COUNT_LANES_ACTIVE - RT_RAY_TYPES];
    w.steps = c[RT_COUNT_WARP_STEPS - RT_RAY_TYPES];
    for (int i = 0; i < RT_PHASES; ++i) w.phases[i] = c[RT_COUNT_PHASES - RT_RAY_TYPES + i];
    return w;
}

void DeviceScene::setArgs(Kernel& k, const dev::RenderSettings& settings) const {
    dev::RenderSettings s = settings;
    s.grid = grid_;
    k.set("spheres", spheres_)
        .set("planes", planes_)
        .set("triangles", triangles_)
        .set("meshes", meshes_)
        .set("kdops", kdops_)
        .set("lights", lights_)
        .set("materials", materials_)
        .set("cubemap", cubemap_)
        .set("bvh", bvh_)
        .set("cells", cells_)
        .set("rayCounts", rayCounts_)
        .set("settings", sizeof s, &s);
}

Launch launch2d(const DeviceInfo& device, int width, int rows) {
    // A fixed work-group shape: PoCL compiles a work-group function per local size, so letting the
    // runtime choose one per tile shape would recompile for every new tile height.
    const size_t lx = device.isGpu() ? 16 : 64, ly = device.isGpu() ? 8 : 1;
    return {cl::NDRange((width + lx - 1) / lx * lx, (rows + ly - 1) / ly * ly),
            cl::NDRange(lx, ly)};
}

int columnStep(const DeviceInfo& device) { return int(launch2d(device, 1, 1).local[0]); }

TileRange tileRange(const DeviceInfo& device, int width, const LaunchTile& tile) {
    if (!tile.partialRow()) {
        Launch rows = launch2d(device, width, tile.rows);
        return {cl::NullRange, rows.global, rows.local};
    }
    const size_t step = size_t(columnStep(device));
    return {cl::NDRange(size_t(tile.col0), 0),
            cl::NDRange((size_t(tile.cols) + step - 1) / step * step, 1), cl::NDRange(step, 1)};
}

}  // namespace rt
