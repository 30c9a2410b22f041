// rtlab-bench — the benchmark harness. Two modes over one measurement protocol (bench/measure.h):
//
//   rtlab-bench [--benchmark_*] [selection flags]   Google Benchmark: one benchmark per scene x
//       pipeline x resolution x bounce limit x accel x device, timed by profiling events (manual
//       time), with per-kernel, ray, memory and tree-use counters. --benchmark_out=FILE.json
//       writes JSON that Google Benchmark's compare.py reads.
//   rtlab-bench --sweep FILE --out DIR              a sweep file's cells with a progress line,
//       on one device or several (--devices), all of them or one share (--shard i/N), rows to
//       DIR/rows.jsonl in cell order as they are measured, kept frames to DIR/images/*.pfm. This is
//       what runs on a GPU machine: it links no OpenImageIO, so `rtlab sweep --import DIR`
//       compares the frames and draws the charts afterwards, elsewhere.
#include <benchmark/benchmark.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "bench/measure.h"
#include "bench/pfm.h"
#include "bench/smoke.h"
#include "bench/sweep_config.h"
#include "bench/sweep_eta.h"
#include "bench/sweep_runner.h"
#include "bench/watchdog.h"
#include "cli/parse_error.h"
#include "core/accel.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "core/version.h"

namespace fs = std::filesystem;
using namespace rt;
using namespace rt::bench;

namespace {

// What rtlab-bench --help says above and below the flags.
const char* kDescription =
    R"(rtlab-bench: the registered pipelines, timed by OpenCL profiling events. Three modes:
  Google Benchmark mode (the default): one benchmark per scene x pipeline x size x bounce limit
      x structure x device, selected by the flags of its group below; every --benchmark_* flag
      works, e.g. --benchmark_filter=REGEX, --benchmark_out=FILE.json, --benchmark_min_time=0.1
  Sweep mode, --sweep=SWEEP --out=DIR: a sweep file's cells, rows to DIR/rows.jsonl and kept
      frames to DIR/images (what `rtlab sweep --import` reads; no Google Benchmark)
  Smoke check, --smoke: one frame of every scene x size x pipeline (both megakernel layouts) x
      structure (the SPD scenes: the first size and the BVH), a PASS or FAIL line each (scripts/gpu-smoke runs it on a GPU host before any
      GPU result is called done))";

const char* kExitStatus = R"(
Exit status: 0 when every benchmark or cell ran; 1 for a bad flag, a selection that matches no
benchmark, a scene that cannot be loaded, or a benchmark or cell that failed (in sweep mode,
cells of stop-after-failure groups may fail: that is what they measure); 130 after Ctrl-C, with
--benchmark_out written for the benchmarks that finished.
)";

struct Flags {
    std::vector<std::string> scenes{"empty", "spheres", "shadows", "cornell", "mesh", "envmap"};
    std::vector<std::string> pipelines = pipelineRegistry().names(true);
    std::vector<std::string> sizes{"640x360", "1280x720", "1920x1080", "3840x2160"};
    std::string bounces = "0..8";
    std::vector<std::string> accels;  // empty: each scene's default
    std::string cells, sweep, out, device, sceneDir, kernelDir, resume, shard;
    std::vector<std::string> devices;
    int repeats = 5, warmup = 2, frames = 5;
    bool countRays = true, listDevices = false, smoke = false;
    std::set<std::string> given;  // the flags on the command line
    double timeLimit = 0;
    double cellTimeout = kDefaultCellTimeoutS;
};

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    size_t a = 0;
    while (a <= s.size()) {
        size_t b = s.find(',', a);
        if (b == std::string::npos) b = s.size();
        if (b > a) out.push_back(s.substr(a, b - a));
        a = b + 1;
    }
    return out;
}

// The flags of every mode, in the groups --help shows them in. CLI11 takes both --flag=value
// and --flag value; a flag given twice keeps its last value. Bad values are refused here, in
// rtlab's one-line form (cli/parse_error.h); names (scenes, pipelines, structures, devices) are
// checked where they are used, against what exists.
void addFlags(CLI::App& app, Flags& f) {
    app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    auto list = [&](const char* name, std::vector<std::string>& into, const char* type,
                    const std::string& help) {
        return app
            .add_option_function<std::string>(
                name, [&into](const std::string& v) { into = split(v); }, help)
            ->type_name(type);
    };

    const char* gbench = "Google Benchmark mode";
    list("--scenes", f.scenes, "a,b,...",
         "Scene names in the scene folder [empty,spheres,shadows,cornell,mesh,envmap]")
        ->group(gbench);
    list("--pipelines", f.pipelines, "a,b,...", "Any registered pipelines (listed below) [all]")
        ->group(gbench);
    list("--sizes", f.sizes, "WxH,...", "[640x360,1280x720,1920x1080,3840x2160]")->group(gbench);
    app.add_option("--bounces", f.bounces, "List and/or ranges [0..8]")
        ->type_name("0..8")
        ->group(gbench);
    list("--accels", f.accels, "bvh,...", "none, bv, grid, bvh, wide, cwbvh [each scene's default]")
        ->group(gbench);
    app.add_option("--cells", f.cells,
                   "Instead of the lists above: the cells of a sweep file (every cell: "
                   "stop-after-failure applies in sweep mode only)")
        ->type_name("SWEEP")
        ->group(gbench);
    app.add_option("--repeats", f.repeats, "Repetitions per benchmark; the median is reported [5]")
        ->type_name("N")
        ->check(CLI::Range(1, 1000))
        ->group(gbench);
    app.add_option("--frames", f.frames,
                   "Timed frames per repetition (fixed, so that sub-millisecond cells do not "
                   "auto-iterate for minutes) [5]")
        ->type_name("N")
        ->check(CLI::Range(1, 100000))
        ->group(gbench);
    app.add_option("--warmup", f.warmup, "Untimed frames before timing [2]")
        ->type_name("N")
        ->check(CLI::Range(0, 100))
        ->group(gbench);
    app.add_option_function<std::string>(
           "--count-rays", [&f](const std::string& v) { f.countRays = v == "yes" || v == "true"; },
           "One untimed frame with device ray counters [yes]")
        ->type_name("yes|no")
        ->check(CLI::IsMember({"yes", "no", "true", "false"}).description(""))
        ->group(gbench);

    const char* sweep = "Sweep mode (no Google Benchmark; what `rtlab sweep --import` reads)";
    app.add_option("--sweep", f.sweep, "Run this sweep file's cells (needs --out)")
        ->type_name("SWEEP")
        ->group(sweep);
    app.add_option("--out", f.out,
                   "Folder for rows.jsonl (one row per cell, in cell order, as they are "
                   "measured), sweep.json and the kept frames (images/*.pfm)")
        ->type_name("DIR")
        ->group(sweep);
    app.add_option("--time-limit", f.timeLimit,
                   "Stop before a cell that would end after this many seconds [0: none]")
        ->type_name("SECONDS")
        ->group(sweep);
    app.add_option("--shard", f.shard,
                   "Run only the work units u with u % N == i, for N machines (merge: `rtlab "
                   "sweep CONFIG --import DIR0 DIR1 ...`); with --smoke, that share of its cells")
        ->type_name("i/N")
        ->group(sweep);
    app.add_option("--resume", f.resume,
                   "Skip the cells an earlier run's rows.jsonl measured (or that timed out); give "
                   "`rtlab sweep --import` both output folders afterwards. Groups with "
                   "stop-after-failure (bench/sweeps/limits) skip the settings no smaller than "
                   "one that failed and write them as rows with status \"skipped\"")
        ->type_name("ROWS,...")
        ->group(sweep);

    app.add_flag("--smoke", f.smoke,
                 "The smoke check, over --scenes, --sizes, --pipelines, --accels and --shard: one "
                 "frame of every scene x size x pipeline (both megakernel layouts) x structure, "
                 "one line each: PASS when it ran, every pixel is finite and it agrees with the "
                 "megakernel's frame (tree layout, the scene's own structure) as two structures "
                 "must; FAIL and why otherwise. Defaults: "
                 "empty,spheres,shadows,cornell,mesh,envmap,divergence at 160x90 and 1920x1080, "
                 "every pipeline and structure. Exit status 1 when a cell fails")
        ->group("Smoke check");

    const char* every = "Every mode";
    app.add_option("--device", f.device,
                   "One OpenCL device by index or name [$RTLAB_DEVICE, else first GPU]")
        ->type_name("SPEC")
        ->group(every);
    list("--devices", f.devices, "SPEC,...",
         "Several OpenCL devices by index or name, or all (every GPU); not with --device. Sweep "
         "mode runs the cells on them at once, one context each, rows in cell order; Google "
         "Benchmark mode registers one set of benchmarks per device")
        ->group(every);
    app.add_option("--cell-timeout", f.cellTimeout,
                   "A benchmark repetition or sweep cell (program builds included) that has not "
                   "finished by then fails with \"timeout\"; 0 = no limit [600]. Google Benchmark "
                   "mode: the later benchmarks are then not run. Sweep mode: after a stuck "
                   "compiler the sweep goes on in a fresh context; after a stuck device it stops "
                   "with every row so far written, and --resume goes on past the cell. Either way "
                   "the exit status is 1")
        ->type_name("SECONDS")
        ->check(CLI::Range(0.0, 1e7))
        ->group(every);
    app.add_option("--scene-dir", f.sceneDir,
                   "Where <scene>.json are [scenes/ of the checkout]; cubemap faces must be .pfm "
                   "(rtlab-bench reads no PNG: see `rtlab sweep --export-scenes`)")
        ->type_name("DIR")
        ->group(every);
    app.add_option("--kernel-dir", f.kernelDir, "Read kernel sources from a source tree [embedded]")
        ->type_name("DIR")
        ->group(every);
    app.add_flag("--list-devices", f.listDevices, "Print the OpenCL devices and exit")
        ->group(every);
    app.set_version_flag("--version", std::string("rtlab-bench ") + RTLAB_COMMIT,
                         "Print the commit this binary was built from and exit");
    app.set_help_flag("-h,--help", "Print this help and exit");
    app.footer(std::string(kExitStatus) +
               "\nPipelines (--pipelines, and `pipelines =` in sweep files):\n" +
               pipelineRegistry().help() +
               "\nGoogle Benchmark's own flags: --benchmark_list_tests, --benchmark_filter, ...");
}

// Cubemap faces without OpenImageIO: .pfm only.
Image readFace(const fs::path& path) {
    std::string ext = path.extension().string();
    if (ext == ".pfm") return readPfm(path);
    throw Error(
        path.string() +
        ": rtlab-bench reads cubemap faces only as .pfm (it links no "
        "OpenImageIO); make a converted scene folder with `rtlab sweep --export-scenes DIR`");
}

int listDevicesCommand() {
    for (const DeviceInfo& d : listDevices())
        std::printf("%d  %s  [%s]  platform %s, driver %s, %u compute units, %.0f MiB\n", d.index,
                    d.name.c_str(), d.type.c_str(), d.platformName.c_str(), d.driver.c_str(),
                    d.computeUnits, double(d.globalMem) / 1048576.0);
    return 0;
}

// ---- sweep mode ----

int sweepCommand(const Flags& f) {
    if (f.out.empty()) throw Error("--sweep needs --out DIR");
    SweepConfig config = loadSweep(findSweep(f.sweep));
    fs::path out(f.out);
    fs::create_directories(out / "images");
    std::ofstream rows(out / "rows.jsonl");
    if (!rows) throw Error((out / "rows.jsonl").string() + ": cannot write");
    SweepRunOptions o;
    o.device = f.device;
    if (!f.devices.empty() && !f.device.empty())
        throw Error("--device and --devices: give one (--devices=" + f.device + " for one device)");
    ClContext::announceBuilds(true);  // a cold GPU host spends seconds on each program
    for (const std::string& d : f.devices) o.devices += (o.devices.empty() ? "" : ",") + d;
    if (!f.shard.empty()) o.shard = parseShard(f.shard);
    o.sceneDir = f.sceneDir;
    o.readImage = readFace;
    o.sources = KernelSources(f.kernelDir);
    o.timeLimitS = f.timeLimit;
    o.cellTimeoutS = f.cellTimeout;
    for (const std::string& file : split(f.resume)) {
        std::ifstream in(file);
        if (!in) throw Error("--resume " + file + ": cannot read");
        std::string line;
        while (std::getline(in, line)) {
            nlohmann::json row = nlohmann::json::parse(line, nullptr, false);
            // A cell that timed out is not run again either: it would most likely hang again.
            if (!row.is_discarded() && row.contains("cell") &&
                (row.value("status", "") == "ok" || row.value("failure", "") == "timeout"))
                o.skip.insert(currentCellKey(row["cell"].get<std::string>()));
        }
    }
    // Frames that are bit-identical (the pipelines share their stage code, so they often
    // are) are stored once: the file count and size that travel back stay small.
    std::map<uint64_t, std::string> stored;
    int unexpectedErrors = 0;  // failed cells outside stop-after-failure groups
    auto writeMeta = [&](const nlohmann::json& meta) {
        std::ofstream(out / "sweep.json") << meta.dump(2) << "\n";
    };
    SweepSummary s =
        runSweep(config, o, writeMeta, [&](const nlohmann::json& row, const Image* image) {
            nlohmann::json r = row;
            if (image) {
                uint64_t h = 1469598103934665603ull ^ uint64_t(image->width) << 32 ^ image->height;
                for (unsigned char c :
                     std::string_view(reinterpret_cast<const char*>(image->rgb.data()),
                                      image->rgb.size() * sizeof(float)))
                    h = (h ^ c) * 1099511628211ull;
                auto [it, fresh] = stored.emplace(h, "images/" + imageName(row));
                r["image"] = it->second;
                if (fresh) writePfm(*image, out / it->second);
            }
            rows << r.dump() << "\n" << std::flush;
            unexpectedErrors +=
                row.value("status", "") == "error" && !row.value("stop_after_failure", false);
        });
    writeMeta(s.meta);
    std::string stopped = s.complete                      ? ""
                          : s.meta.contains("stopped_by") ? " (stopped by a timeout on the device)"
                                                          : " (stopped by the time limit)";
    std::fprintf(stderr,
                 "sweep %s: %d of %d cells measured, %d failed, %d not run after a failure, "
                 "%d done before, in %s%s -> %s\n",
                 config.name.c_str(), s.measured, s.cells, s.failed, s.notRun, s.skipped,
                 formatDuration(s.seconds).c_str(), stopped.c_str(), out.string().c_str());
    if (s.timedOut) {
        std::fprintf(stderr, "rtlab-bench: %d cell(s) timed out (their rows say where)\n",
                     s.timedOut);
        return 1;
    }
    if (unexpectedErrors) {
        std::fprintf(stderr, "rtlab-bench: %d cell(s) failed (their rows say why)\n",
                     unexpectedErrors);
        return 1;
    }
    return 0;
}

// ---- smoke check ----

int smokeCommand(const Flags& f) {
    for (const char* only : {"--sweep", "--cells", "--bounces", "--resume", "--devices"})
        if (f.given.count(only)) throw Error(std::string(only) + ": not with --smoke");
    SmokeOptions o = defaultSmokeOptions();
    if (f.given.count("--scenes")) {
        o.scenes = f.scenes;
        o.spotScenes.clear();  // the scenes asked for, no others
    }
    if (f.given.count("--sizes")) o.sizes = f.sizes;
    if (f.given.count("--pipelines")) o.pipelines = f.pipelines;
    if (f.given.count("--accels")) o.accels = f.accels;
    for (const std::string& a : o.accels) (void)parseAccel(a);  // a bad name ends here, in one line
    o.sceneDir = f.sceneDir;
    o.readImage = readFace;
    o.sources = KernelSources(f.kernelDir);
    o.device = f.device;
    if (!f.shard.empty()) o.shard = parseShard(f.shard);
    o.cellTimeoutS = f.cellTimeout;
    ClContext::announceBuilds(true);  // the GPU host's log shows what each process compiles
    SmokeSummary s = runSmoke(o, stdout);
    std::printf("smoke: %d of %d cells passed%s\n", s.passed, s.cells,
                s.stopped ? " (stopped: a device call did not return)" : "");
    return s.failed ? 1 : 0;
}

// ---- Google Benchmark mode ----

struct Target {
    std::unique_ptr<ClContext> cl;
    std::string tag;  // "" for one device, else "/dev<index>"
};

// Progress over every registered repetition, and Ctrl-C: once interrupted, the running and
// every later benchmark ends at once with an error, so Google Benchmark still writes
// --benchmark_out for the ones that finished. The time left is the sweep's estimate
// (bench/sweep_eta.h) over the repetitions not yet run, in registration order.
struct Progress {
    int total = 0, done = 0, failed = 0;
    bool filtered = false;  // --benchmark_filter may leave fewer than `total` to run
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    std::vector<Cell> cells;  // one per registered benchmark
    std::vector<int> left;    // its repetitions not yet run
    SweepEta eta;
} progress;
volatile std::sig_atomic_t interrupted = 0;
void onInterrupt(int) { interrupted = 1; }

void reportProgress(size_t slot, const std::string& name, double msPerFrame, bool ok,
                    double seconds, double buildSeconds) {
    ++progress.done;
    progress.failed += !ok;
    progress.eta.measured(progress.cells[slot], seconds, buildSeconds, ok);
    if (progress.left[slot] > 0) --progress.left[slot];
    double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - progress.start).count();
    std::vector<const Cell*> pending;
    for (size_t i = 0; i < progress.cells.size(); ++i)
        for (int r = 0; r < progress.left[i]; ++r) pending.push_back(&progress.cells[i]);
    double left = progress.eta.remaining(pending);
    char result[64] = "failed";
    if (ok) std::snprintf(result, sizeof result, "%.3f ms/frame", msPerFrame);
    std::fprintf(stderr, "[%d/%s%d] %s: %s | elapsed %s, ETA %s%s\n", progress.done,
                 progress.filtered ? "at most " : "", progress.total, name.c_str(), result,
                 formatDuration(elapsed).c_str(), progress.filtered ? "<= " : "",
                 formatDuration(left).c_str());
}

// --cell-timeout, and the benchmark that passed it (the later ones are then not run: the
// device's state after a stuck call is unknown).
double cellTimeoutS = kDefaultCellTimeoutS;
std::string timedOut;

void renderBenchmark(benchmark::State& state, size_t slot, const std::string& name, ClContext* cl,
                     const Scene* scene, std::string kind, RenderOptions o, int warmup,
                     bool countRays) {
    if (interrupted) {
        state.SkipWithError("interrupted");
        return;
    }
    if (!timedOut.empty()) {
        state.SkipWithError(("not run: " + timedOut + " timed out before it").c_str());
        return;
    }
    struct Report {  // one progress line per repetition, however it ends
        benchmark::State& state;
        size_t slot;
        const std::string& name;
        const ClContext& cl;
        double ms = 0;
        std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
        double programMs = cl.programCounts().ms;
        ~Report() {
            double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            reportProgress(slot, name, ms, !state.error_occurred(), s,
                           (cl.programCounts().ms - programMs) / 1e3);
        }
    } report{state, slot, name, *cl};
    // Every device call of the repetition runs under the cell time limit; work that overruns it
    // keeps the pipeline (shared) and is never waited for again.
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(cellTimeoutS);
    auto guarded = [&](auto work) {
        double left = cellTimeoutS <= 0
                          ? 0
                          : std::max(1e-3, std::chrono::duration<double>(
                                               deadline - std::chrono::steady_clock::now())
                                               .count());
        if (withinSeconds(left, work)) return true;
        timedOut = name;
        std::string building = cl->building();
        char why[128];
        std::snprintf(why, sizeof why,
                      "timeout: did not finish within %g s (--cell-timeout): ", cellTimeoutS);
        state.SkipWithError((why + (building.empty() ? "the device or its driver did not return"
                                                     : "the OpenCL compiler did not finish "
                                                       "building " +
                                                           building))
                                .c_str());
        return false;
    };
    size_t before = cl->allocatedBytes();
    std::shared_ptr<Pipeline> pipeline;
    try {
        pipeline = makePipeline(kind, cl);
        o.countRays = false;
        if (!guarded([pipeline, scene, o, warmup] {
                for (int i = 0; i < warmup; ++i) pipeline->render(*scene, o);
                return true;
            }))
            return;
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
        return;
    }
    double wall = 0;
    std::map<std::string, double> kernels;
    for (auto _ : state) {
        if (interrupted) {
            state.SkipWithError("interrupted");
            break;
        }
        try {
            if (!guarded([pipeline, scene, o] {
                    pipeline->render(*scene, o);
                    return true;
                }))
                break;
        } catch (const std::exception& e) {
            state.SkipWithError(e.what());
            break;
        }
        const FrameStats& s = pipeline->stats();
        state.SetIterationTime(s.deviceMs * 1e-3);
        wall += s.hostMs;
        for (const auto& [name, ms] : s.kernelMs) kernels[name] += ms;
    }
    if (state.error_occurred()) return;
    using benchmark::Counter;
    const FrameStats& s = pipeline->stats();
    double devSum = 0;
    for (const auto& [name, ms] : kernels) {
        devSum += ms;
        state.counters["k_" + name + "_ms"] = Counter(ms, Counter::kAvgIterations);
    }
    state.counters["ms_per_frame"] = Counter(devSum, Counter::kAvgIterations);
    report.ms = state.iterations() ? devSum / double(state.iterations()) : 0;
    state.counters["wall_ms"] = Counter(wall, Counter::kAvgIterations);
    state.counters["device_bytes"] = double(cl->allocatedBytes() - before);
    state.counters["private_bytes"] = double(s.privateBytes);
    state.counters["tree_nodes"] = double(treeNodeCount(scene->branching(), o.bounces));
    state.counters["tiles"] = s.tiles;
    // Numeric extras of the last timed frame (the wavefront's tree_used, the queue's span_ms and
    // idle_ms, ...): timings must not come from the ray-counting frame, whose atomics slow it.
    const nlohmann::json timedExtras = s.extras;
    for (const auto& [key, value] : timedExtras.items())
        if (value.is_number()) state.counters[key] = value.get<double>();
    if (countRays) {
        Measurement m;
        m.deviceMs = state.iterations() ? devSum / double(state.iterations()) : 0;
        try {
            o.countRays = true;
            if (!guarded([pipeline, scene, o] {
                    pipeline->render(*scene, o);
                    return true;
                }))
                return;
            m.rays = pipeline->stats().rays;
            m.raysCounted = pipeline->stats().raysCounted;
            m.extras = pipeline->stats().extras;
        } catch (const std::exception& e) {
            state.SetLabel(std::string("ray count failed: ") + e.what());
        }
        deriveRayCounters(m);
        if (m.raysCounted) {
            for (int i = 0; i < RT_RAY_TYPES; ++i)
                state.counters[std::string("rays_") + rayTypeName(i)] = double(m.rays[size_t(i)]);
            state.counters["Mrays_per_s"] = m.mrays;
        }
        // What only the counting frame knows (the share of tree slots used, ...).
        for (const auto& [key, value] : m.extras.items())
            if (value.is_number() && !timedExtras.contains(key))
                state.counters[key] = value.get<double>();
    }
}

std::vector<int> bounceList(const std::string& spec) {
    SweepConfig c = parseSweep("[x]\nscenes = x\nbounces = " + spec + "\n", "--bounces");
    return c.groups[0].bounces;
}

int benchmarkCommand(const Flags& f) {
    if (!f.shard.empty())
        throw Error("--shard: only with --sweep (the Google Benchmark mode runs no work units)");
    // The same --devices specs as the sweep mode (all, indices, names); one benchmark set each.
    std::string spec;
    for (const std::string& d : f.devices) spec += (spec.empty() ? "" : ",") + d;
    std::vector<DeviceInfo> chosen =
        spec.empty() ? std::vector<DeviceInfo>{selectDevice(f.device)} : selectDevices(spec);
    std::vector<Target> targets;
    for (const DeviceInfo& device : chosen) {
        Target t;
        t.cl = std::make_unique<ClContext>(device, KernelSources(f.kernelDir));
        if (chosen.size() > 1) {
            t.tag = "/dev" + std::to_string(device.index);
            for (const Target& other : targets)  // a device named twice: a second set of its own
                if (other.tag == t.tag) t.tag += "-" + std::to_string(targets.size());
        }
        const DeviceInfo& d = t.cl->device();
        std::string prefix = chosen.size() > 1 ? t.tag.substr(1) + "_" : "";
        benchmark::AddCustomContext(prefix + "device", d.name);
        benchmark::AddCustomContext(prefix + "device_slug", deviceSlug(d));
        benchmark::AddCustomContext(prefix + "platform", d.platformName);
        benchmark::AddCustomContext(prefix + "driver", d.driver);
        targets.push_back(std::move(t));
    }
    benchmark::AddCustomContext("rtlab_commit", RTLAB_COMMIT);
    benchmark::AddCustomContext("rtlab_timing",
                                "manual time = device ms per frame (profiling "
                                "events, sum over kernels) after " +
                                    std::to_string(f.warmup) + " warm-up frames");

    // A scene that cannot be loaded (a PNG cubemap, say) ends the run with its reason: a
    // benchmark that silently leaves a scene out reads as a complete one.
    static std::map<std::string, Scene> scenes;
    auto scene = [&](const std::string& name) -> const Scene* {
        if (auto it = scenes.find(name); it != scenes.end()) return &it->second;
        try {
            return &scenes.emplace(name, loadScene(scenePath(name, f.sceneDir), readFace))
                        .first->second;
        } catch (const Error& e) {
            throw Error("scene " + name + ": " + e.what());
        }
    };

    std::vector<Cell> cells;
    if (!f.cells.empty()) {
        SweepConfig config = loadSweep(findSweep(f.cells));
        for (const std::string& s : sweepScenes(config)) scene(s);  // load, or report and drop
        for (SweepGroup& g : config.groups)
            std::erase_if(g.scenes, [&](const std::string& s) { return !scenes.count(s); });
        std::erase_if(config.groups, [](const SweepGroup& g) { return g.scenes.empty(); });
        cells =
            expandCells(config, [&](const std::string& n) -> const Scene& { return *scene(n); });
    } else {
        std::vector<int> bounces = bounceList(f.bounces);
        for (const std::string& name : f.scenes) {
            const Scene* s = scene(name);
            if (!s) continue;
            for (const std::string& size : f.sizes)
                for (int b : bounces)
                    for (const std::string& accel :
                         f.accels.empty() ? std::vector<std::string>{accelName(s->defaults.accel)}
                                          : f.accels)
                        for (const std::string& p : f.pipelines) {
                            Cell c;
                            c.scene = name;
                            c.pipeline = pipelineInfo(p).name;
                            c.options = s->defaults;
                            if (std::sscanf(size.c_str(), "%dx%d", &c.options.width,
                                            &c.options.height) != 2 ||
                                c.options.width < 1 || c.options.height < 1)
                                throw Error("--sizes " + size +
                                            ": expected WIDTHxHEIGHT, both at least 1");
                            c.options.bounces = b;
                            c.options.accel = parseAccel(accel);
                            c.accelApplies = !s->triangles.empty() || !s->spheres.empty();
                            cells.push_back(c);
                        }
        }
    }
    for (Target& t : targets)
        for (const Cell& c : cells) {
            const RenderOptions& o = c.options;
            std::string name = "render/" + c.scene + "/" + c.pipeline + "/" +
                               std::to_string(o.width) + "x" + std::to_string(o.height) + "/b" +
                               std::to_string(o.bounces) + "/s" + std::to_string(o.shadowSamples) +
                               "/aa" + std::to_string(o.aa) + "/" +
                               (c.accelApplies ? accelName(o.accel) : "-");
            // A pipeline's own options, where not at their defaults, tell apart cells that
            // differ only in them (the megakernel's layouts, the queue's shade modes).
            for (const PipelineOption* opt : pipelineRegistry().options())
                if (!opt->isDefault(o.pipelineOptions))
                    name += "/" + opt->sweepKey + "=" + opt->text(opt->value(o.pipelineOptions));
            name += t.tag;
            // What the estimate knows of it: the frames of one repetition, and a scene name per
            // device, since each device has its own speed and its own built programs.
            Cell timed = c;
            timed.scene += t.tag;
            timed.warmup = f.warmup;
            timed.repeats = f.frames;
            timed.countRays = f.countRays && c.countRays;
            progress.cells.push_back(timed);
            progress.left.push_back(f.repeats);
            benchmark::RegisterBenchmark(name.c_str(), renderBenchmark, progress.cells.size() - 1,
                                         name, t.cl.get(), scene(c.scene), c.pipeline, o, f.warmup,
                                         f.countRays && c.countRays)
                ->UseManualTime()
                ->Iterations(f.frames)
                ->Unit(benchmark::kMillisecond)
                ->Repetitions(f.repeats)
                ->DisplayAggregatesOnly(f.repeats > 1);
        }
    if (cells.empty()) throw Error("no benchmark matches the selection (see --help)");
    progress.total = int(cells.size() * targets.size()) * f.repeats;
    cellTimeoutS = f.cellTimeout;
    std::signal(SIGINT, onInterrupt);
    size_t ran = benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    if (interrupted) {
        std::fprintf(stderr,
                     "rtlab-bench: interrupted after %d repetitions; results so far written\n",
                     progress.done);
        return 130;
    }
    if (ran == 0) throw Error("no benchmark matches --benchmark_filter");
    if (!timedOut.empty()) {
        // The stuck call may still use its context: it must outlive this function.
        for (Target& t : targets) (void)t.cl.release();
        std::fprintf(stderr,
                     "rtlab-bench: %s timed out (--cell-timeout %g); the benchmarks after "
                     "it were not run\n",
                     timedOut.c_str(), cellTimeoutS);
        return 1;
    }
    if (progress.failed) {
        std::fprintf(stderr, "rtlab-bench: %d of %d repetitions failed (their errors are above)\n",
                     progress.failed, progress.done);
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Flags f;
    CLI::App app{kDescription, "rtlab-bench"};
    addFlags(app, f);
    // Google Benchmark answers --help with its own flags alone and exits: ours come first.
    for (int i = 1; i < argc; ++i)
        if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
            std::fputs(app.help().c_str(), stdout);
            return 0;
        }
    // Google Benchmark takes its --benchmark_* flags out of argv; the rest are ours.
    for (int i = 1; i < argc; ++i)
        progress.filtered |= std::strncmp(argv[i], "--benchmark_filter", 18) == 0;
    benchmark::Initialize(&argc, argv);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return cli::reportParseError(app, e, "rtlab-bench", argc, argv);
    }
    for (const CLI::Option* opt : app.get_options())
        if (opt->count() && !opt->get_lnames().empty())
            f.given.insert("--" + opt->get_lnames().front());
    try {
        if (f.listDevices) return listDevicesCommand();
        int status = f.smoke            ? smokeCommand(f)
                     : !f.sweep.empty() ? sweepCommand(f)
                                        : benchmarkCommand(f);
        // A thread is still stuck in the driver: exit without destructors or exit handlers,
        // which could wait on it.
        if (workAbandoned()) {
            std::fflush(nullptr);
            std::_Exit(status);
        }
        return status;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab-bench: %s\n", e.what());
        if (workAbandoned()) {
            std::fflush(nullptr);
            std::_Exit(1);
        }
        return 1;
    }
}
