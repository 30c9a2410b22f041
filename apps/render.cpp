// rtlab render / rtlab devices.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "apps/options.h"
#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/version.h"
#include "core/pipeline.h"
#include "pipelines/registry.h"
#include "core/scene_loader.h"
#include "image/image_io.h"

namespace rt::cli {

namespace {

struct RenderArgs {
    std::string scene, output, pipeline;  // the first device pipeline registered, by default
    SceneFlags flags;
    bool stats = false;
    std::string statsJson;  // --stats-json FILE
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
    const char* unit = a.name == "bvh" || a.name == "wide" || a.name == "cwbvh" ? "nodes" : a.name == "grid" ? "cells" : "volumes";
    std::printf("  accel        %s, %lld %s (%s), %s; built in %.1f ms\n", a.name.c_str(), a.nodes,
                unit, mib(double(a.bytes)).c_str(), a.detail.c_str(), a.buildMs);
}

// A progress bar on stderr for a frame that takes more than about a second, when stderr is a
// terminal; it draws from the pipeline's progress reports (Pipeline::setProgress) and erases
// itself when the frame ends, so that what stays on the terminal is only the render's output.
class ProgressBar {
public:
    explicit ProgressBar(std::string label)
        : label_(std::move(label)), enabled_(isatty(STDERR_FILENO) == 1) {}
    ~ProgressBar() { clear(); }
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;

    void update(long long done, long long total) {
        if (!enabled_ || total <= 0) return;
        auto now = Clock::now();
        double elapsed = std::chrono::duration<double>(now - start_).count();
        // Quiet for the first second (most frames end before), then at most 10 lines a second.
        if (elapsed < 1.0 || (drawn_ && now - lastDraw_ < std::chrono::milliseconds(100))) return;
        lastDraw_ = now;
        drawn_ = true;
        double f = std::clamp(double(done) / double(total), 0.0, 1.0);
        constexpr int kWidth = 30;
        int filled = int(f * kWidth);
        std::string bar = std::string(size_t(filled), '#') + std::string(size_t(kWidth - filled), '-');
        char eta[32] = "ETA ?";
        if (done > 0) std::snprintf(eta, sizeof eta, "ETA %.1f s", elapsed * (1 - f) / f);
        std::fprintf(stderr, "\r\033[K%s [%s] %3.0f%%  elapsed %.1f s  %s", label_.c_str(),
                     bar.c_str(), 100 * f, elapsed, eta);
        std::fflush(stderr);
    }
    void clear() {
        if (!drawn_) return;
        std::fprintf(stderr, "\r\033[K");
        std::fflush(stderr);
        drawn_ = false;
    }
    Pipeline::Progress callback() {
        return [this](long long done, long long total) { update(done, total); };
    }

private:
    using Clock = std::chrono::steady_clock;
    std::string label_;
    bool enabled_, drawn_ = false;
    Clock::time_point start_ = Clock::now(), lastDraw_{};
};

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
    const PipelineInfo& info = pipelineInfo(a.pipeline);
    std::string output = a.output.empty() ? "render.png" : a.output;
    // Fail on an unwritable output before spending time on the frame.
    checkOutputPath(output);
    Scene scene = loadScene(a.scene, readImage);
    for (const std::string& note : scene.notes) std::fprintf(stderr, "rtlab: note: %s\n", note.c_str());
    RenderOptions options = a.flags.apply(scene.defaults);
    std::optional<ClContext> cl;
    if (!info.reference) cl.emplace(selectDevice(a.flags.device), a.flags.kernelSources());
    std::unique_ptr<Pipeline> pipeline = makePipeline(info.name, cl ? &*cl : nullptr);
    if (!a.statsJson.empty()) {
        std::ofstream probe(a.statsJson, std::ios::app);
        if (!probe) throw Error("--stats-json " + a.statsJson + ": cannot write there");
    }
    Image image;
    {
        ProgressBar bar("rendering");
        pipeline->setProgress(bar.callback());
        image = pipeline->render(scene, options);
        pipeline->setProgress({});
    }
    writeImage(image, output);
    FrameStats timed = pipeline->stats();
    if (a.stats || !a.statsJson.empty()) {
        FrameStats& s = timed;
        // Ray counts come from one more, untimed frame: the device counters' atomics cost time.
        RayCounts rays{};
        bool counted = false;
        if (!info.reference) {
            RenderOptions counting = options;
            counting.countRays = true;
            ProgressBar bar("counting rays");
            pipeline->setProgress(bar.callback());
            pipeline->render(scene, counting);
            pipeline->setProgress({});
            rays = pipeline->stats().rays;
            counted = pipeline->stats().raysCounted;
            s.rays = rays;
            s.raysCounted = counted;
            // What only the counted frame knows (the queue's retraced_rays) joins the extras.
            for (const auto& [key, value] : pipeline->stats().extras.items())
                if (!s.extras.contains(key)) s.extras[key] = value;
        }
        uint64_t totalRays = 0;
        for (uint64_t n : rays) totalRays += n;
        const double raysPerS = s.deviceMs > 0 ? double(totalRays) / (s.deviceMs * 1e-3) : 0;
        if (!a.statsJson.empty()) {
            nlohmann::json j = {{"scene", scene.name}, {"pipeline", info.name},
                                {"width", options.width}, {"height", options.height},
                                {"bounces", options.bounces}, {"commit", RTLAB_COMMIT},
                                {"device", cl ? cl->device().name : std::string("cpu reference")},
                                {"driver", cl ? cl->device().driver : std::string()},
                                {"device_ms", s.deviceMs}, {"host_ms", s.hostMs},
                                {"launches", s.launches}, {"longest_launch_ms", s.longestLaunchMs},
                                {"tiles", s.tiles}, {"private_bytes", s.privateBytes},
                                {"extras", s.extras}};
            for (const auto& [name, ms] : s.kernelMs) j["kernel_ms"][name] = ms;
            for (const auto& [name, bytes] : s.buffers) j["buffers"][name] = bytes;
            if (counted) {
                for (int t = 0; t < RT_RAY_TYPES; ++t) j["rays"][rayTypeName(t)] = rays[t];
                j["rays_per_s"] = raysPerS;
            }
            std::ofstream f(a.statsJson);
            f << j.dump(2) << "\n";
            if (!f) throw Error("--stats-json " + a.statsJson + ": cannot write");
        }
    }
    if (a.stats) {
        const FrameStats& s = timed;
        std::printf("scene %s, %dx%d, bounces %d, C=%d, N=%lld nodes/pixel, pipeline %s\n",
                    scene.name.c_str(), options.width, options.height, options.bounces,
                    scene.branching(), treeNodeCount(scene.branching(), options.bounces),
                    info.name.c_str());
        if (cl)
            std::printf("device %s, program %s\n", cl->device().label().c_str(),
                        s.program.c_str());
        for (const auto& [name, ms] : s.kernelMs)
            std::printf("  %-12s %10.3f ms\n", name.c_str(), ms);
        if (!info.reference) std::printf("  %-12s %10.3f ms\n", "device total", s.deviceMs);
        std::printf("  %-12s %10.3f ms\n", "host", s.hostMs);
        for (const auto& [name, bytes] : s.buffers)
            std::printf("  %-12s %zu bytes (%s)\n", name.c_str(), bytes, mib(double(bytes)).c_str());
        if (info.supports.tiling)
            std::printf("  tiles        %d\n", s.tiles);  // the tree's bytes a pixel: in extras
        if (!info.reference) {
            std::printf("  private      %zu bytes per work-item\n", s.privateBytes);
            printAccel(s.accel, options.accel);
        }
        for (const auto& [key, value] : s.extras.items())
            std::printf("  %-12s %s\n", key.c_str(), value.dump().c_str());
        std::printf("  launches     %d, longest %.3f ms", s.launches, s.longestLaunchMs);
        if (options.maxLaunchMs > 0) std::printf(" (--max-launch-ms %g caps each launch)", options.maxLaunchMs);
        std::printf("\n");
        if (s.raysCounted) {
            uint64_t total = 0;
            for (int t = 0; t < RT_RAY_TYPES; ++t) {
                std::printf("  rays %-7s %llu\n", rayTypeName(t), (unsigned long long)s.rays[t]);
                total += s.rays[t];
            }
            if (s.deviceMs > 0)
                std::printf("  rays/s       %.3g (all types, over the timed frame's device time)\n",
                            double(total) / (s.deviceMs * 1e-3));
        }
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
    a.pipeline = pipelineRegistry().names(true).at(0);
    addPipelineOption(*renderCmd, a.pipeline, true);
    a.flags.add(*renderCmd);
    renderCmd->add_flag("--stats", a.stats,
                        "Print kernel times (profiling events), memory use, launches and ray "
                        "counts (from one more, untimed frame)");
    renderCmd->add_option("--stats-json", a.statsJson,
                          "Write the same statistics as JSON to this file, for scripts");
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
