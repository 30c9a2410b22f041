// rtlab render / rtlab devices.
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "apps/options.h"
#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "image/image_io.h"

namespace rt::cli {

namespace {

struct RenderArgs {
    std::string scene, output, pipeline = "mega";
    SceneFlags flags;
    bool stats = false;
} renderArgs;

CLI::App* renderCmd = nullptr;
CLI::App* devicesCmd = nullptr;

std::string mib(double bytes) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / (1024.0 * 1024.0));
    return buf;
}

// Which acceleration structure ran (issue 5); its size and build time when the pipeline
// reported them (DeviceScene::accelStats).
void printAccel(const AccelStats& a, RenderOptions::Accel chosen) {
    if (a.name.empty()) {
        std::printf("  accel        %s\n", accelName(chosen));
        return;
    }
    if (a.name == "none") {
        std::printf("  accel        none (preliminary checks only)\n");
        return;
    }
    const char* unit = a.name == "bvh" ? "nodes" : a.name == "grid" ? "cells" : "volumes";
    std::printf("  accel        %s, %lld %s (%s), %s; built in %.1f ms\n", a.name.c_str(), a.nodes,
                unit, mib(double(a.bytes)).c_str(), a.detail.c_str(), a.buildMs);
}

// The queue pipeline's pool and its queue lengths per bounce (wavefront/queue).
void printQueue(const FrameStats& s) {
    std::printf("  pool         %zu rays, %zu bytes (%s), %d bounce iterations, %lld paths restarted\n",
                s.poolRays, s.poolBytes, mib(double(s.poolBytes)).c_str(), s.iterations,
                s.restartedPaths);
    std::printf("  queues       bounce %10s %10s %10s %10s %10s\n", "miss", "diffuse", "mirror", "glass",
                "procedural");
    for (size_t d = 0; d < s.queueLengths.size(); ++d) {
        const auto& q = s.queueLengths[d];
        std::printf("               %6zu %10lld %10lld %10lld %10lld %10lld\n", d, q[0], q[1], q[2], q[3],
                    q[4]);
    }
}

int runDevices() {
    std::vector<DeviceInfo> devices = listDevices();
    if (devices.empty()) {
        std::fprintf(stderr, "rtlab: no OpenCL device found (run scripts/setup to install PoCL)\n");
        return 1;
    }
    std::string chosen;
    try {
        chosen = selectDevice("").name;
    } catch (const Error&) {
    }
    for (const DeviceInfo& d : devices) {
        std::printf("%c %d  %s  [%s]\n", d.name == chosen ? '*' : ' ', d.index, d.name.c_str(),
                    d.type.c_str());
        std::printf("      platform %s, %s, %s, driver %s\n", d.platformName.c_str(),
                    d.version.c_str(), d.openclC.c_str(), d.driver.c_str());
        std::printf("      %u compute units, %s global memory, %s max allocation\n",
                    d.computeUnits, mib(double(d.globalMem)).c_str(),
                    mib(double(d.maxAlloc)).c_str());
    }
    std::printf("(* = default; choose with --device INDEX|NAME or RTLAB_DEVICE)\n");
    return 0;
}

int runRender() {
    RenderArgs& a = renderArgs;
    PipelineKind kind = parsePipeline(a.pipeline);
    std::string output = a.output.empty() ? "render.png" : a.output;
    // Fail on an unwritable output before spending time on the frame.
    checkOutputPath(output);
    Scene scene = loadScene(a.scene, readImage);
    for (const std::string& note : scene.notes) std::fprintf(stderr, "rtlab: note: %s\n", note.c_str());
    RenderOptions options = a.flags.apply(scene.defaults);
    std::optional<ClContext> cl;
    if (kind != PipelineKind::Cpu) cl.emplace(selectDevice(a.flags.device), a.flags.kernelSources());
    std::unique_ptr<Pipeline> pipeline = makePipeline(kind, cl ? &*cl : nullptr);
    Image image = pipeline->render(scene, options);
    writeImage(image, output);
    if (a.stats) {
        const FrameStats& s = pipeline->stats();
        std::printf("scene %s, %dx%d, bounces %d, C=%d, N=%lld nodes/pixel, pipeline %s\n",
                    scene.name.c_str(), options.width, options.height, options.bounces,
                    s.branching, s.treeNodes, pipelineName(kind));
        if (cl)
            std::printf("device %s, program %s\n", cl->device().label().c_str(),
                        s.program.c_str());
        for (const auto& [name, ms] : s.kernelMs)
            std::printf("  %-12s %10.3f ms\n", name.c_str(), ms);
        if (kind != PipelineKind::Cpu) std::printf("  %-12s %10.3f ms\n", "device total", s.deviceMs);
        std::printf("  %-12s %10.3f ms\n", "host", s.hostMs);
        if (kind == PipelineKind::Wave)
            std::printf("  ray tree     %zu bytes (%s) in %d tile(s), %zu B node\n", s.treeBytes,
                        mib(double(s.treeBytes)).c_str(), s.tiles, sizeof(dev::Node));
        if (kind == PipelineKind::Queue) printQueue(s);
        if (kind != PipelineKind::Cpu)
            std::printf("  private      %zu bytes per work-item\n", s.privateBytes);
        if (kind != PipelineKind::Cpu) printAccel(s.accel, options.accel);
    }
    std::printf("wrote %s\n", output.c_str());
    return 0;
}

}  // namespace

void addRender(CLI::App& app) {
    RenderArgs& a = renderArgs;
    renderCmd = app.add_subcommand("render", "Render a scene (.json) or a bare model (.obj) to an image");
    renderCmd->add_option("scene", a.scene, "Scene file (.json, see scenes/README.md) or OBJ model")
        ->required();
    renderCmd->add_option("-o,--output", a.output,
                          "Output image: .png (8-bit sRGB, clamped) or .exr (linear float) "
                          "[render.png]");
    renderCmd->add_option("--pipeline", a.pipeline,
                          "cpu (double-precision reference), mega, wave or queue")
        ->check(CLI::IsMember({"cpu", "mega", "wave", "queue"}))
        ->capture_default_str();
    a.flags.add(*renderCmd);
    renderCmd->add_flag("--stats", a.stats, "Print kernel times (profiling events) and memory use");
}

void addDevices(CLI::App& app) {
    devicesCmd = app.add_subcommand("devices", "List every OpenCL platform and device");
}

int run(CLI::App& app) {
    (void)app;
    if (renderCmd && renderCmd->parsed()) return runRender();
    if (devicesCmd && devicesCmd->parsed()) return runDevices();
    if (compareParsed()) return runCompare();
    return runSweepCommand();
}

}  // namespace rt::cli
