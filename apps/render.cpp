// rtlab render / rtlab devices.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <variant>

#include "apps/commands.h"
#include "apps/options.h"
#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "core/version.h"
#include "image/image_io.h"
#include "pipelines/registry.h"

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

// Which acceleration structure ran; its size and build time when the pipeline
// reported them (DeviceScene::accelStats).
void printAccel(std::FILE* out, const AccelStats& a, RenderOptions::Accel chosen) {
    if (a.name.empty()) {
        std::fprintf(out, "  accel        %s\n", accelName(chosen));
        return;
    }
    if (a.name == "none") {
        std::fprintf(out, "  accel        none (preliminary checks only)\n");
        return;
    }
    const char* unit = a.name == "bvh" || a.name == "wide" || a.name == "cwbvh" ? "nodes"
                       : a.name == "grid"                                       ? "cells"
                                                                                : "volumes";
    std::fprintf(out, "  accel        %s, %lld %s (%s), %s; built in %.1f ms\n", a.name.c_str(),
                 a.nodes, unit, mib(double(a.bytes)).c_str(), a.detail.c_str(), a.buildMs);
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
        std::string bar =
            std::string(size_t(filled), '#') + std::string(size_t(kWidth - filled), '-');
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
        std::printf("      %u compute units, %s global memory, %s max allocation\n", d.computeUnits,
                    mib(double(d.globalMem)).c_str(), mib(double(d.maxAlloc)).c_str());
        std::printf("      at most %zu work-items a work-group, %llu KiB local memory",
                    d.maxWorkGroup, static_cast<unsigned long long>(d.localMem / 1024));
        if (d.registersPerGroup != 0) std::printf(", %u registers", d.registersPerGroup);
        std::printf("\n");
    }
    std::printf("(* = default; choose with --device INDEX|NAME or RTLAB_DEVICE)\n");
    return 0;
}

// A statistic for people and scripts alike: milliseconds and other floats to 3 decimals (a
// microsecond), the rest as they are, arrays and objects element by element.
nlohmann::json rounded(const nlohmann::json& v) {
    if (v.is_number_float()) return std::round(v.get<double>() * 1e3) / 1e3;
    if (v.is_array() || v.is_object()) {
        nlohmann::json out = v;
        for (auto& x : out) x = rounded(x);
        return out;
    }
    return v;
}

// "2 built (13.2 s), 1 from the disk cache": how a frame's programs were obtained.
std::string describePrograms(const ClContext::ProgramCounts& c) {
    std::string out;
    auto part = [&](int n, const char* what) {
        if (n) out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    part(c.built, "built");
    part(c.fromDisk, "from the disk cache");
    part(c.fromMemory, "already in memory");
    char ms[48];
    std::snprintf(ms, sizeof ms, " (%.1f ms)", c.ms);
    return (out.empty() ? "none" : out) + (c.built || c.fromDisk ? ms : "");
}

int runRender() {
    RenderArgs& a = renderArgs;
    const PipelineInfo& info = pipelineInfo(a.pipeline);
    std::string output = a.output.empty() ? "render.png" : a.output;
    // Fail on an unwritable output before spending time on the frame.
    checkOutputPath(output);
    Scene scene = loadScene(a.scene, readImage);
    for (const std::string& note : scene.notes)
        std::fprintf(stderr, "rtlab: note: %s\n", note.c_str());
    RenderOptions options = a.flags.apply(scene.defaults);
    std::optional<ClContext> cl;
    if (!info.reference) cl.emplace(selectDevice(a.flags.device), a.flags.kernelSources());
    std::unique_ptr<Pipeline> pipeline = makePipeline(info.name, cl ? &*cl : nullptr);
    const bool jsonToStdout = a.statsJson == "-";
    if (!a.statsJson.empty() && !jsonToStdout) {
        std::ofstream probe(a.statsJson, std::ios::app);
        if (!probe) throw Error("--stats-json " + a.statsJson + ": cannot write there");
    }
    Image image;
    ClContext::ProgramCounts before = cl ? cl->programCounts() : ClContext::ProgramCounts{};
    {
        ProgressBar bar("rendering");
        pipeline->setProgress(bar.callback());
        image = pipeline->render(scene, options);
        pipeline->setProgress({});
    }
    ClContext::ProgramCounts programs = cl ? cl->programCounts() : ClContext::ProgramCounts{};
    programs.built -= before.built;
    programs.fromDisk -= before.fromDisk;
    programs.fromMemory -= before.fromMemory;
    programs.ms -= before.ms;
    writeImage(image, output);
    FrameStats s = pipeline->stats();
    if (!s.note.empty()) std::fprintf(stderr, "%s\n", s.note.c_str());
    // The frame's host time without the program builds and loads it waited for.
    const double frameHostMs = std::max(0.0, s.hostMs - programs.ms);
    if (a.stats || !a.statsJson.empty()) {
        // Ray counts come from one more, untimed frame: the device counters' atomics cost time.
        if (!info.reference) {
            RenderOptions counting = options;
            counting.countRays = true;
            ProgressBar bar("counting rays");
            pipeline->setProgress(bar.callback());
            pipeline->render(scene, counting);
            pipeline->setProgress({});
            s.rays = pipeline->stats().rays;
            s.raysCounted = pipeline->stats().raysCounted;
            // What only the counted frame knows (the queue's retraced_rays, the megakernel's
            // busy lanes per warp) joins the extras.
            for (const auto& [key, value] : pipeline->stats().extras.items())
                if (!s.extras.contains(key)) s.extras[key] = value;
        }
    }
    uint64_t totalRays = 0;
    for (uint64_t n : s.rays) totalRays += n;
    const double raysPerS = s.deviceMs > 0 ? double(totalRays) / (s.deviceMs * 1e-3) : 0;
    const bool capped = options.maxLaunchMs > 0;
    if (!a.statsJson.empty()) {
        nlohmann::json j = {{"scene", scene.name},
                            {"pipeline", info.name},
                            {"width", options.width},
                            {"height", options.height},
                            {"bounces", options.bounces},
                            {"shadow_samples", options.shadowSamples},
                            {"aa", options.aa},
                            {"adaptive", options.adaptiveAa},
                            {"accel", accelName(options.accel)},
                            {"max_launch_ms", options.maxLaunchMs},
                            {"commit", RTLAB_COMMIT},
                            {"device", cl ? cl->device().name : std::string("cpu reference")},
                            {"driver", cl ? cl->device().driver : std::string()},
                            {"device_ms", rounded(s.deviceMs)},
                            {"host_ms", rounded(frameHostMs)},
                            {"programs",
                             {{"built", programs.built},
                              {"from_disk", programs.fromDisk},
                              {"in_memory", programs.fromMemory},
                              {"ms", rounded(programs.ms)}}},
                            {"launches", s.launches},
                            {"longest_launch_ms", rounded(s.longestLaunchMs)},
                            {"private_bytes", s.privateBytes},
                            {"extras", rounded(s.extras)}};
        if (info.supports.tiling) j["tiles"] = s.tiles;
        // Every registered pipeline option under its row field: the value where the pipeline
        // rendered declares it ("layout": "tree"), "-" where it does not.
        for (const PipelineOption* opt : pipelineRegistry().options()) j[opt->field()] = "-";
        for (const PipelineOption& opt : info.options) {
            const OptionValue& v = opt.value(options.pipelineOptions);
            if (const long long* n = std::get_if<long long>(&v))
                j[opt.field()] = *n;
            else
                j[opt.field()] = std::get<std::string>(v);
        }
        for (const auto& [name, ms] : s.kernelMs) j["kernel_ms"][name] = rounded(ms);
        for (const auto& [name, bytes] : s.buffers) j["buffers"][name] = bytes;
        if (s.raysCounted) {
            for (int t = 0; t < RT_RAY_TYPES; ++t) j["rays"][rayTypeName(t)] = s.rays[t];
            j["rays_per_s"] = std::round(raysPerS);
        }
        if (jsonToStdout) {
            std::printf("%s\n", j.dump(2).c_str());
        } else {
            std::ofstream f(a.statsJson);
            f << j.dump(2) << "\n";
            if (!f) throw Error("--stats-json " + a.statsJson + ": cannot write");
        }
    }
    if (a.stats) {
        // With the JSON on standard output, the table goes to standard error.
        std::FILE* out = jsonToStdout ? stderr : stdout;
        std::fprintf(out,
                     "scene %s, %dx%d, bounces %d, shadow samples %d, aa %d%s, accel %s, C=%d, "
                     "N=%lld nodes/pixel, pipeline %s",
                     scene.name.c_str(), options.width, options.height, options.bounces,
                     options.shadowSamples, options.aa, options.adaptiveAa ? " adaptive" : "",
                     accelName(options.accel), scene.branching(),
                     treeNodeCount(scene.branching(), options.bounces), info.name.c_str());
        // The pipeline's own options: " (layout tree)". A number at a default outside its
        // range (one the pipeline chooses) reads "default".
        std::string own;
        for (const PipelineOption& opt : info.options) {
            const OptionValue& v = opt.value(options.pipelineOptions);
            const long long* n = std::get_if<long long>(&v);
            const bool chosen =
                n && opt.isDefault(options.pipelineOptions) && (*n < opt.min || *n > opt.max);
            own += (own.empty() ? "" : ", ") + opt.name + " " +
                   (chosen ? std::string("default") : opt.text(v));
        }
        if (!own.empty()) std::fprintf(out, " (%s)", own.c_str());
        std::fprintf(out, "\n");
        if (cl) {
            std::fprintf(out, "device %s\n", cl->device().label().c_str());
            std::fprintf(out, "  programs     %s\n", describePrograms(programs).c_str());
        }
        for (const auto& [name, ms] : s.kernelMs)
            std::fprintf(out, "  %-12s %10.3f ms\n", name.c_str(), ms);
        if (!info.reference) std::fprintf(out, "  %-12s %10.3f ms\n", "device total", s.deviceMs);
        std::fprintf(
            out, "  %-12s %10.3f ms%s\n", "host", frameHostMs,
            programs.ms > 0 ? " (the frame alone: program builds and loads not counted)" : "");
        for (const auto& [name, bytes] : s.buffers)
            std::fprintf(out, "  %-12s %zu bytes (%s)\n", name.c_str(), bytes,
                         mib(double(bytes)).c_str());
        if (info.supports.tiling)
            std::fprintf(
                out,
                "  tiles        %d (launches of rows; memory_tiles: those the tree's memory "
                "needed)\n",
                s.tiles);
        if (!info.reference) {
            std::fprintf(out, "  private      %zu bytes per work-item\n", s.privateBytes);
            printAccel(out, s.accel, options.accel);
        }
        for (const auto& [key, value] : s.extras.items())
            std::fprintf(out, "  %-12s %s\n", key.c_str(), rounded(value).dump().c_str());
        std::fprintf(out, "  launches     %d, longest %.3f ms", s.launches, s.longestLaunchMs);
        if (capped)
            std::fprintf(out, " (--max-launch-ms %g: %s)", options.maxLaunchMs,
                         s.longestLaunchMs <= options.maxLaunchMs
                             ? "every launch kept to it"
                             : "some launch passed it; pieces are sized from launches timed "
                               "before them");
        std::fprintf(out, "\n");
        if (s.raysCounted) {
            for (int t = 0; t < RT_RAY_TYPES; ++t)
                std::fprintf(out, "  rays %-7s %llu\n", rayTypeName(t),
                             (unsigned long long)s.rays[t]);
            if (s.deviceMs > 0)
                std::fprintf(
                    out, "  rays/s       %.3g (all types, over the timed frame's device time)\n",
                    raysPerS);
        }
    }
    if (!jsonToStdout) std::printf("wrote %s\n", output.c_str());
    return 0;
}

}  // namespace

void addRender(CLI::App& app) {
    RenderArgs& a = renderArgs;
    renderCmd = app.add_subcommand(
        "render", "Render a scene (.json or .nff) or a bare model (.obj, ...) to an image");
    renderCmd
        ->add_option("scene", a.scene,
                     "Scene file (.json, see scenes/README.md; .nff, see docs/NFF.md) or model")
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
                          "Write the same statistics as JSON to this file (- for standard output, "
                          "then nothing else is printed there), for scripts");
}

void addDevices(CLI::App& app) {
    devicesCmd = app.add_subcommand("devices", "List every OpenCL platform and device");
}

int run(CLI::App& app) {
    (void)app;
    if (renderCmd && renderCmd->parsed()) return runRender();
    if (devicesCmd && devicesCmd->parsed()) return runDevices();
    if (compareParsed()) return runCompare();
    if (predictParsed()) return runPredict();
    if (int listed = runLists(); listed >= 0) return listed;
    return runSweepCommand();
}

}  // namespace rt::cli
