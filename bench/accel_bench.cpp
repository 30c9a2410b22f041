// rtlab-accel-bench — the acceleration structures' acceptance measurement: on big-mesh
// (1,002,528 triangles) at bounce limit 2, rays per second of device time with --accel bvh over
// the full 1280x720 frame, and with --accel none over a centred crop of it (brute force tests
// every ray against a million triangles, so on a CPU only a crop keeps its frame short), both in
// one run. The ratio is reported as the counter bvh_over_none; the acceptance bar is >= 1000 on
// PoCL.
//
//   rtlab-accel-bench [--benchmark_*]     environment:
//     RTLAB_STRESS_DIR  folder of big-mesh.json [scenes/stress; generated there when missing]
//     RTLAB_DEVICE      OpenCL device [first GPU, else CPU]
//     RTLAB_CROP        crop of the none frame, WxH with even margins [8x6]
//
// Rays are counted on the device (RT_COUNT_RAYS) in an untimed frame for bvh, whose atomics
// would distort a timed frame, and in the timed frame itself for none, whose atomics are
// nothing next to a million triangle tests per ray.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>
#include <string>

#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "pipelines/registry.h"

namespace fs = std::filesystem;
using namespace rt;

namespace {

fs::path bigMesh() {
    const char* env = std::getenv("RTLAB_STRESS_DIR");
    fs::path dir = env && *env ? fs::path(env) : fs::path(RTLAB_SOURCE_DIR) / "scenes" / "stress";
    fs::path scene = dir / "big-mesh.json";
    if (!fs::exists(scene) || !fs::exists(dir / "models" / "big-mesh.obj")) {
        std::string cmd = "python3 " +
                          (fs::path(RTLAB_SOURCE_DIR) / "scripts" / "make-stress.py").string() +
                          " --only mesh --out " + dir.string();
        std::fprintf(stderr, "generating %s\n", scene.c_str());
        if (std::system(cmd.c_str()) != 0) throw Error("failed: " + cmd);
    }
    return scene;
}

uint64_t totalRays(const FrameStats& s) {
    return std::accumulate(s.rays.begin(), s.rays.end(), uint64_t(0));
}

// Device time and rays of one frame; counts rays in that frame when `count` is set.
struct Frame {
    double ms;
    uint64_t rays;
};
Frame frame(Pipeline& p, const Scene& scene, RenderOptions o, bool count) {
    o.countRays = count;
    p.render(scene, o);
    return {p.stats().deviceMs, count ? totalRays(p.stats()) : 0};
}

void BigMeshBvhOverNone(benchmark::State& state, const std::string& kind) {
    try {
        std::optional<ClContext> cl;
        const char* dev = std::getenv("RTLAB_DEVICE");
        cl.emplace(selectDevice(dev ? dev : ""), KernelSources(""));
        Scene scene = loadScene(bigMesh());
        auto pipeline = makePipeline(kind, &*cl);
        RenderOptions o = scene.defaults;  // 1280x720
        o.bounces = 2;
        o.aa = 1;
        o.accel = RenderOptions::Accel::Bvh;

        int cw = 8, ch = 6;
        if (const char* c = std::getenv("RTLAB_CROP"); c && std::sscanf(c, "%dx%d", &cw, &ch) != 2)
            throw Error(std::string("RTLAB_CROP ") + c + ": expected WxH");
        Scene cropped = scene;
        RenderOptions crop = o;
        cropToCenter(cropped, crop, cw, ch);
        crop.accel = RenderOptions::Accel::None;

        for (auto _ : state) {
            Frame warm = frame(*pipeline, scene, o, true);  // builds program and BVH; counts rays
            Frame bvh = frame(*pipeline, scene, o, false);
            Frame none = frame(*pipeline, cropped, crop, true);
            state.SetIterationTime((bvh.ms + none.ms) / 1000.0);
            double bvhRate = double(warm.rays) / (bvh.ms / 1000.0);
            double noneRate = double(none.rays) / (none.ms / 1000.0);
            state.counters["bvh_rays_per_s"] = bvhRate;
            state.counters["none_rays_per_s"] = noneRate;
            state.counters["bvh_over_none"] = bvhRate / noneRate;
            state.counters["bvh_ms"] = bvh.ms;
            state.counters["none_ms"] = none.ms;
        }
        state.SetLabel(cl->device().name + ", none on a " + std::to_string(cw) + "x" +
                       std::to_string(ch) + " crop");
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

}  // namespace

// One benchmark per registered device pipeline, named after it (BigMeshBvhOverNone/mega, ...).
int main(int argc, char** argv) {
    for (const std::string& name : rt::pipelineRegistry().names(true))
        benchmark::RegisterBenchmark(("BigMeshBvhOverNone/" + name).c_str(), BigMeshBvhOverNone,
                                     name)
            ->Iterations(1)
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
