// rtlab bench — the sweep loop (see sweep_runner.h).
#include "bench/sweep_runner.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "bench/frame_check.h"
#include "bench/measure.h"
#include "bench/sweep_eta.h"
#include "bench/sweep_schedule.h"
#include "bench/watchdog.h"
#include "core/accel.h"
#include "core/error.h"
#include "core/version.h"
#include "pipelines/registry.h"

namespace rt::bench {
namespace fs = std::filesystem;

namespace {

std::string utcNow() {
    std::time_t t = std::time(nullptr);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
    return buf;
}

// The progress line. Cells run out of order when several devices share a sweep: the count
// shown is of cells finished, and the time left is the not yet started cells' estimate shared
// out over the workers. Callers hold the sweep's lock.
class Progress {
  public:
    Progress(const std::vector<Cell>& cells, const std::vector<size_t>& toRun, int workers)
        : cells_(cells),
          pending_(cells.size(), 0),
          total_(toRun.size()),
          workers_(workers),
          tty_(isatty(fileno(stderr))),
          start_(std::chrono::steady_clock::now()) {
        // Cells that stop-after-failure may skip are counted in: the ETA is then a bound.
        for (size_t i : toRun) {
            pending_[i] = 1;
            mayStop_ = mayStop_ || cells[i].stopAfterFailure;
        }
    }
    double elapsed() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }
    // Seconds a cell should take, its program build included unless a cell of the same program
    // started before it (bench/sweep_eta.h).
    double estimate(size_t i) const { return eta_.estimate(cells_[i]); }
    double remaining() const {
        std::vector<const Cell*> pending;
        for (size_t i = 0; i < cells_.size(); ++i)
            if (pending_[i]) pending.push_back(&cells_[i]);
        return eta_.remaining(pending) / workers_;
    }
    // The time left as shown: nothing until two cells were measured (one cell's rate, stretched
    // over a whole sweep, said "ETA <= 7h13m" for a 3-minute run), and a bound ("<=") where
    // stop-after-failure may skip cells.
    std::string eta() const {
        if (measured_ < 2) return "estimating";
        return std::string(mayStop_ ? "<= " : "") + formatDuration(remaining());
    }
    void starting(const std::vector<size_t>& run, const std::string& where) {
        for (size_t i : run) {
            pending_[i] = 0;
            eta_.started(cells_[i]);
        }
        if (!tty_) return;
        std::string what = cells_[run.front()].label() + where;
        if (run.size() > 1) what += " (+" + std::to_string(run.size() - 1) + " interleaved)";
        std::fprintf(stderr, "\r\033[K[%zu/%zu] %s ... | elapsed %s, ETA %s", done_ + 1, total_,
                     what.c_str(), formatDuration(elapsed()).c_str(), eta().c_str());
        std::fflush(stderr);
    }
    void skipped(size_t i, const std::string& why) {
        const Cell& c = cells_[i];
        pending_[i] = 0;
        ++done_;
        std::fprintf(stderr, "%s[%zu/%zu] %s: skipped | elapsed %s\n    %s\n",
                     tty_ ? "\r\033[K" : "", done_, total_, c.label().c_str(),
                     formatDuration(elapsed()).c_str(), why.c_str());
        std::fflush(stderr);
    }
    // seconds: the cell's share of its batch, buildSeconds of them in program builds.
    void finished(size_t i, double seconds, double buildSeconds, const Measurement& m,
                  const std::string& where) {
        const Cell& c = cells_[i];
        eta_.measured(c, seconds, buildSeconds, m.ok);
        ++measured_;
        ++done_;
        char result[96];
        if (m.ok)
            std::snprintf(result, sizeof result, "%.3f ms", m.deviceMs);
        else
            std::snprintf(result, sizeof result, "failed");
        std::fprintf(stderr, "%s[%zu/%zu] %s%s: %s | elapsed %s, ETA %s%s", tty_ ? "\r\033[K" : "",
                     done_, total_, c.label().c_str(), where.c_str(), result,
                     formatDuration(elapsed()).c_str(), eta().c_str(), tty_ ? "" : "\n");
        if (!m.ok) std::fprintf(stderr, "%s    %s\n", tty_ ? "\n" : "", m.error.c_str());
        std::fflush(stderr);
    }
    void done() {
        if (tty_) std::fprintf(stderr, "\n");
    }

  private:
    const std::vector<Cell>& cells_;
    std::vector<char> pending_;  // to run and not yet started
    size_t total_, done_ = 0;
    int workers_;
    bool tty_, mayStop_ = false;
    std::chrono::steady_clock::time_point start_;
    int measured_ = 0;
    SweepEta eta_;
};

nlohmann::json rowJson(const SweepConfig& config, const Cell& c, const Measurement& m,
                       const nlohmann::json& device, const nlohmann::json& scene,
                       const std::string& skipped = "") {
    const RenderOptions& o = c.options;
    nlohmann::json row = {
        {"sweep", config.name},
        {"cell", c.key()},
        {"groups", c.groups},
        {"scene", c.scene},
        {"pipeline", c.pipeline},
        {"pipeline_title", pipelineInfo(c.pipeline).title},
        {"family", pipelineInfo(c.pipeline).family},
        // Extra compiler options an experiment built every program with (register-study).
        {"cl_options", std::getenv("RTLAB_CL_OPTIONS") ? std::getenv("RTLAB_CL_OPTIONS") : ""},
        {"width", o.width},
        {"height", o.height},
        {"bounces", o.bounces},
        {"shadow_samples", o.shadowSamples},
        {"aa", o.aa},
        {"accel", c.accelApplies ? accelName(o.accel) : "-"},
        {"memory_budget", o.memoryBudget},
        {"adaptive", o.adaptiveAa},
        {"max_launch_ms", o.maxLaunchMs},
        {"robust_sphere", o.robustSphere},
        {"watertight", o.watertight},
        {"scaled_offset", o.offset != RenderOptions::Offset::Fixed},  // old column: not fixed
        {"offset", offsetName(o.offset)},
        {"warmup", c.warmup},
        {"repeats", c.repeats},
        {"status", m.ok              ? "ok"
                   : skipped.empty() ? "error"
                                     : "skipped"},
        {"error", m.error},
    };
    // Every registered pipeline option, as the cell set it (its default where it did not), under
    // its row field: "layout": "weighted", "pool": 4096. And under "options" the ones the cell's
    // own pipeline declares, which tell its variants apart in charts and tables.
    auto json = [](const OptionValue& v) {
        const long long* n = std::get_if<long long>(&v);
        return n ? nlohmann::json(*n) : nlohmann::json(std::get<std::string>(v));
    };
    for (const PipelineOption* opt : pipelineRegistry().options())
        row[opt->field()] = json(opt->value(o.pipelineOptions));
    nlohmann::json own = nlohmann::json::object();
    for (const PipelineOption& opt : pipelineInfo(c.pipeline).options)
        own[opt.name] = json(opt.value(o.pipelineOptions));
    row["options"] = own;
    if (c.stopAfterFailure) row["stop_after_failure"] = true;
    if (c.maxFrameS > 0) row["max_frame_s"] = c.maxFrameS;
    if (!skipped.empty()) row["skip_reason"] = skipped;
    // The kind is the one the error was thrown with (rt::Error's FailureKind), never read from
    // the message; a cell that failed without one is "other".
    FailureKind failure = !skipped.empty()                 ? FailureKind::Skipped
                          : m.ok                           ? FailureKind::None
                          : m.failure == FailureKind::None ? FailureKind::Other
                                                           : m.failure;
    row["failure"] = failureKindName(failure);
    if (m.ok) {
        nlohmann::json kernels = nlohmann::json::object();
        for (const auto& [name, ms] : m.kernelMs) kernels[name] = ms;
        row.update({{"device_ms", m.deviceMs},
                    {"device_ms_min", m.deviceMsMin},
                    {"device_ms_max", m.deviceMsMax},
                    {"wall_ms", m.wallMs},
                    {"frame_ms", m.frameMs},
                    {"kernel_ms", kernels},
                    {"device_bytes", m.deviceBytes},
                    {"tree_bytes", m.extras.value("tree_bytes", size_t(0))},
                    {"private_bytes", m.privateBytes},
                    {"kernel_resources", m.kernelResources},
                    {"tree_nodes", treeNodeCount(c.branching, o.bounces)},
                    {"branching", c.branching},
                    {"tiles", m.tiles},
                    {"launches", m.launches},
                    {"longest_launch_ms", m.longestLaunchMs},
                    {"frames", m.frames},
                    {"accel_build_ms", m.accelBuildMs},
                    {"program_ms", m.programMs}});
        nlohmann::json buffers = nlohmann::json::object();
        for (const auto& [name, bytes] : m.buffers) buffers[name] = bytes;
        row["buffers"] = buffers;
        row["extras"] = m.extras;
        row["memory_tiles"] = memoryTiles(row);
        if (m.raysCounted) {
            nlohmann::json rays = nlohmann::json::object();
            for (int t = 0; t < RT_RAY_TYPES; ++t) rays[rayTypeName(t)] = m.rays[size_t(t)];
            row["rays"] = rays;
            row["mrays_per_s"] = m.mrays;
            if (m.extras.contains("tree_used")) row["tree_used"] = m.extras["tree_used"];
        }
    }
    row["end"] = endState(row);
    row["scene_info"] = scene;
    row.update(device);  // device, driver, platform, commit on every row
    return row;
}

// How a batch's frame time divides among its cells (fractions, parallel to run): by the host
// wall time each measured per frame times its frames, where every cell of the batch ran (the
// frames are interleaved, so each took what it measured), else by the rough cost model.
std::vector<double> batchShares(const std::vector<Cell>& cells, const std::vector<size_t>& run,
                                std::map<size_t, Measurement>& ms) {
    std::vector<double> weight, rough;
    for (size_t k : run) {
        const Measurement& m = ms[k];
        const Cell& c = cells[k];
        weight.push_back(m.ok ? m.wallMs * (c.warmup + m.frames + (c.countRays ? 1 : 0)) : 0);
        rough.push_back(roughCost(c));
    }
    if (std::find(weight.begin(), weight.end(), 0.0) != weight.end()) weight = rough;
    double sum = 0;
    for (double w : weight) sum += w;
    for (double& w : weight) w /= sum;
    return weight;
}

// The largest |difference| of two frames of one size, or -1 when the sizes differ.
double maxDifference(const Image& a, const Image& b) {
    FrameAgreement d = compareFrames(a, b, 0);
    return d.sameSize ? d.maxAbs : -1;
}

// The host's load averages: other work on the machine skews CPU-device timings (PoCL) most.
std::string loadAverage() {
    std::ifstream f("/proc/loadavg");
    std::string one, five, fifteen;
    f >> one >> five >> fifteen;
    return f ? one + " " + five + " " + fifteen : "unknown";
}

}  // namespace

int memoryTiles(const nlohmann::json& row) {
    // The pipeline counted its tiles (FrameStats::extras); rows without them ran in one piece.
    if (row.contains("extras") && row["extras"].contains("memory_tiles"))
        return row["extras"]["memory_tiles"].get<int>();
    return 1;
}

std::string endState(const nlohmann::json& row) {
    std::string status = row.value("status", "");
    if (status == "skipped") return "skipped";
    if (status != "ok") return "error: " + row.value("error", std::string());
    int tiles = memoryTiles(row);
    return tiles > 1 ? "ran (tiled into " + std::to_string(tiles) + " tiles)" : "ran";
}

std::string formatDuration(double s) {
    if (!(s >= 0) || s > 1e7) return "?";
    long t = std::lround(s);
    char buf[32];
    if (t >= 3600)
        std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, t / 60 % 60);
    else if (t >= 60)
        std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
    else
        std::snprintf(buf, sizeof buf, "%lds", t);
    return buf;
}

fs::path scenePath(const std::string& name, const fs::path& sceneDir) {
    fs::path p(name);
    if (p.has_extension()) {
        // A file named inside the scene folder (real/2CylinderEngine.glb, a model that must not
        // be wrapped in a scene file, which would replace its materials) is found there, so that
        // a sweep reads the same on a GPU host's --scene-dir as in the checkout.
        const fs::path dir = sceneDir.empty() ? fs::path("scenes") : sceneDir;
        if (p.is_relative() && !fs::exists(p) && fs::exists(dir / p)) return dir / p;
        return p;
    }
    if (!sceneDir.empty()) return sceneDir / (name + ".json");
    if (fs::exists(fs::path("scenes") / (name + ".json")))
        return fs::path("scenes") / (name + ".json");
    return fs::path(RTLAB_SOURCE_DIR) / "scenes" / (name + ".json");
}

std::string imageName(const nlohmann::json& row) {
    std::string name = row.at("scene").get<std::string>() + "-" +
                       row.at("pipeline").get<std::string>() + "-" +
                       std::to_string(row.at("width").get<int>()) + "x" +
                       std::to_string(row.at("height").get<int>()) + "-b" +
                       std::to_string(row.at("bounces").get<int>()) + "-s" +
                       std::to_string(row.at("shadow_samples").get<int>()) + "-aa" +
                       std::to_string(row.at("aa").get<int>());
    std::string accel = row.at("accel");
    if (accel != "-") name += "-" + accel;
    // Each pipeline option off its default: "-weighted".
    for (const PipelineOption* opt : pipelineRegistry().options()) {
        if (!row.contains(opt->field())) continue;
        const nlohmann::json& v = row.at(opt->field());
        const std::string text =
            v.is_number_integer() ? std::to_string(v.get<long long>()) : v.get<std::string>();
        if (text != opt->text(opt->defaultValue)) name += "-" + text;
    }
    if (row.at("adaptive").get<bool>()) name += "-adaptive";
    for (char& c : name)
        if (!std::isalnum((unsigned char)c) && c != '-' && c != '.' && c != '_') c = '_';
    return name + ".pfm";
}

nlohmann::json sweepSettingsJson(const SweepConfig& c) {
    nlohmann::json groups = nlohmann::json::array();
    for (const SweepGroup& g : c.groups) groups.push_back(g.name);
    return {{"repeats", c.repeats},
            {"warmup", c.warmup},
            {"count_rays", c.countRays},
            {"reference",
             {{"pipeline", "cpu"},
              {"bounces", c.referenceBounces},
              {"shadow_samples", c.referenceShadowSamples},
              {"aa", c.referenceAa}}},
            {"groups", groups},
            {"timing",
             "device time = sum of the frame's kernels by OpenCL profiling events; "
             "median of `repeats` frames after `warmup` untimed ones; rays counted "
             "in one further untimed frame"}};
}

namespace {

// One cell's outcome, waiting for its turn in the output.
struct Result {
    nlohmann::json row;
    std::optional<Image> image;
};

// What the workers share; every member is guarded by `lock`.
struct SweepState {
    std::mutex lock;
    Progress* progress = nullptr;
    SweepSummary* summary = nullptr;
    size_t nextUnit = 0;
    bool started = false, stop = false;  // a batch began; the time limit (or an error) stops all
    std::exception_ptr error;
    std::map<size_t, Result> results;  // by cell index, until every earlier cell is out
    std::vector<size_t> order;         // the cells to run, in cell order
    size_t emitted = 0;                // order[0, emitted) went to the sink
};

}  // namespace

SweepSummary runSweep(const SweepConfig& config, const SweepRunOptions& options,
                      const std::function<void(const nlohmann::json&)>& onStart,
                      const RowSink& sink) {
    // Shared: a measurement that overruns the cell time limit keeps its scene and context.
    std::map<std::string, std::shared_ptr<const Scene>> scenes;
    std::map<std::string, nlohmann::json> sceneInfo;
    for (const std::string& name : sweepScenes(config)) {
        scenes.emplace(name, std::make_shared<const Scene>(
                                 loadScene(scenePath(name, options.sceneDir), options.readImage)));
        sceneInfo[name] = sceneJson(*scenes.at(name));
    }
    // The whole sweep's cells and units, whatever shard and resume leave of them: cell and unit
    // indices are then the same on every machine.
    const std::vector<Cell> cells =
        expandCells(config, [&](const std::string& n) -> const Scene& { return *scenes.at(n); });
    std::vector<WorkUnit> units;
    std::vector<char> inShard(cells.size(), 0);
    {
        std::vector<WorkUnit> all = workUnits(cells);
        for (size_t u = 0; u < all.size(); ++u) {
            if (int(u % size_t(options.shard.count)) != options.shard.index) continue;
            for (auto [i, j] : all[u].batches)
                for (size_t k = i; k < j; ++k) inShard[k] = 1;
            units.push_back(std::move(all[u]));
        }
    }
    SweepState state;
    SweepSummary summary;
    for (size_t k = 0; k < cells.size(); ++k) {
        if (!inShard[k]) continue;
        if (options.skip.count(cells[k].key()))
            ++summary.skipped;
        else
            state.order.push_back(k);
    }

    std::vector<DeviceInfo> devices = options.devices.empty()
                                          ? std::vector<DeviceInfo>{selectDevice(options.device)}
                                          : selectDevices(options.devices);
    std::vector<std::shared_ptr<ClContext>> contexts;
    for (const DeviceInfo& d : devices)
        contexts.push_back(std::make_shared<ClContext>(d, options.sources));
    nlohmann::json device = deviceJson(devices.front());
    summary.cells = int(state.order.size());
    summary.meta = {{"sweep", config.name},
                    {"config_file", config.path.string()},
                    {"config", config.text},
                    {"settings", sweepSettingsJson(config)},
                    {"scenes", sceneInfo},
                    {"started", utcNow()},
                    {"host_load_start", loadAverage()},
                    {"cells", state.order.size()},
                    {"cell_timeout_s", options.cellTimeoutS},
                    {"skipped_as_done", summary.skipped}};
    summary.meta.update(device);
    if (!options.shard.whole()) {
        summary.meta["shard"] = options.shard.str();
        summary.meta["sweep_cells"] = cells.size();
    }
    std::string on = devices.front().label();
    if (devices.size() > 1) {
        nlohmann::json list = nlohmann::json::array();
        on = std::to_string(devices.size()) + " contexts:";
        for (size_t w = 0; w < devices.size(); ++w) {
            list.push_back(deviceJson(devices[w]));
            list.back()["device_index"] = devices[w].index;
            on += (w ? ", d" : " d") + std::to_string(w) + " = " + devices[w].label();
            if (devices[w].name != devices.front().name)
                std::fprintf(stderr,
                             "sweep %s: warning: the devices differ (%s, %s); each row "
                             "names its own\n",
                             config.name.c_str(), devices.front().name.c_str(),
                             devices[w].name.c_str());
        }
        summary.meta["devices"] = list;
    }
    std::fprintf(stderr, "sweep %s: %zu cells%s on %s, commit %s\n", config.name.c_str(),
                 state.order.size(),
                 options.shard.whole() ? "" : (" (shard " + options.shard.str() + ")").c_str(),
                 on.c_str(), RTLAB_COMMIT);
    if (onStart) onStart(summary.meta);

    Progress progress(cells, state.order, int(devices.size()));
    state.progress = &progress;
    state.summary = &summary;

    // Hands finished rows to the sink in cell order, as far as every earlier cell is done
    // (all: also past cells that never ran, at the end).
    auto emit = [&](bool all) {
        for (; state.emitted < state.order.size(); ++state.emitted) {
            auto it = state.results.find(state.order[state.emitted]);
            if (it == state.results.end()) {
                if (all) continue;
                return;
            }
            sink(it->second.row, it->second.image ? &*it->second.image : nullptr);
            state.results.erase(it);
        }
    };

    auto worker = [&](size_t w) {
        std::shared_ptr<ClContext> cl = contexts[w];  // replaced after a stuck program build
        nlohmann::json where = deviceJson(cl->device());
        where["device_index"] = cl->device().index;
        std::string tag = devices.size() > 1 ? " on d" + std::to_string(w) : "";
        for (;;) {
            size_t u;
            {
                std::lock_guard<std::mutex> hold(state.lock);
                if (state.stop || state.nextUnit == units.size()) return;
                u = state.nextUnit++;
            }
            std::vector<Stop> stops;  // cells of this unit that failed or ran past max-frame-s
            for (auto [i, j] : units[u].batches) {
                std::vector<size_t> here;
                for (size_t k = i; k < j; ++k)
                    if (!options.skip.count(cells[k].key())) here.push_back(k);
                if (here.empty()) continue;
                // stop-after-failure: cells no smaller than one that stopped are recorded, not run.
                std::vector<size_t> run;
                std::map<size_t, std::string> skipWhy;
                for (size_t k : here) {
                    if (cells[k].stopAfterFailure) skipWhy[k] = skipReason(config, cells[k], stops);
                    if (skipWhy[k].empty()) run.push_back(k);
                }
                if (!run.empty()) {
                    std::lock_guard<std::mutex> hold(state.lock);
                    if (state.stop) return;
                    double predicted = 0;
                    for (size_t k : run) predicted += progress.estimate(k);
                    if (options.timeLimitS > 0 && state.started &&
                        progress.elapsed() + predicted > options.timeLimitS) {
                        std::fprintf(stderr,
                                     "\nsweep %s: stopping before %s, the time limit of "
                                     "%s would pass\n",
                                     config.name.c_str(), cells[run.front()].label().c_str(),
                                     formatDuration(options.timeLimitS).c_str());
                        summary.complete = false;
                        state.stop = true;
                        return;
                    }
                    state.started = true;
                    progress.starting(run, tag);
                }
                const Cell& c = cells[i];
                std::map<size_t, Measurement> ms;
                double seconds = 0;
                if (!run.empty()) {
                    std::vector<Variant> variants;
                    bool keep = false;
                    double cap = 0;
                    for (size_t k : run) {
                        variants.push_back({cells[k].pipeline, cells[k].options});
                        // The limits cells keep their frames: the pipelines' images must agree.
                        keep = keep || cells[k].images || cells[k].stopAfterFailure;
                        if (cells[k].maxFrameS > 0)
                            cap = cap > 0 ? std::min(cap, cells[k].maxFrameS) : cells[k].maxFrameS;
                    }
                    auto t0 = std::chrono::steady_clock::now();
                    // A limits batch gets a context of its own: drivers keep memory per context
                    // (NVIDIA reserves private memory for the largest kernel it ran), so a
                    // wavefront cell after the megakernel's deepest cells could fail where it
                    // runs in a new process.
                    std::shared_ptr<ClContext> ctx =
                        c.stopAfterFailure
                            ? std::make_shared<ClContext>(cl->device(), options.sources)
                            : cl;
                    std::shared_ptr<const Scene> scene = scenes.at(c.scene);
                    const double limit = options.cellTimeoutS * double(run.size());
                    auto got = withinSeconds(limit, [=, warmup = c.warmup, repeats = c.repeats,
                                                     countRays = c.countRays] {
                        return measureCells(*ctx, *scene, variants, warmup, repeats, countRays,
                                            keep, cap);
                    });
                    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
                                  .count();
                    if (got) {
                        for (size_t r = 0; r < run.size(); ++r) ms[run[r]] = std::move((*got)[r]);
                    } else {
                        // The thread keeps ctx and scene; this worker never touches ctx again.
                        const std::string compiling = ctx->building();
                        char head[160];
                        std::snprintf(head, sizeof head,
                                      "did not finish within %g s (cell time "
                                      "limit %g s%s): ",
                                      limit, options.cellTimeoutS,
                                      run.size() > 1 ? (" x " + std::to_string(run.size()) +
                                                        " cells measured together")
                                                           .c_str()
                                                     : "");
                        std::string why =
                            head + (compiling.empty() ? std::string("the device or its driver "
                                                                    "did not return")
                                                      : "the OpenCL compiler did not finish "
                                                        "building " +
                                                            compiling);
                        for (size_t k : run) {
                            Measurement& m = ms[k];
                            m.error = why;
                            m.failure = FailureKind::Timeout;
                        }
                        std::lock_guard<std::mutex> hold(state.lock);
                        summary.timedOut += int(run.size());
                        if (!compiling.empty() && ctx == cl) {
                            // Nothing of this context runs on the device: go on in a new one.
                            cl = std::make_shared<ClContext>(cl->device(), options.sources);
                        } else if (compiling.empty()) {
                            // What the device runs, or the driver's state, is unknown: what is
                            // measured after it could not be trusted. Stop here.
                            std::fprintf(stderr,
                                         "\nsweep %s: %s timed out on the device; "
                                         "stopping (rows so far are written; --resume "
                                         "goes on past it)\n",
                                         config.name.c_str(), cells[run.front()].label().c_str());
                            summary.complete = false;
                            summary.meta["stopped_by"] = "timeout: " + cells[run.front()].label();
                            state.stop = true;
                        }
                    }
                }
                // The batch's time less its program builds, shared out over its cells.
                const std::vector<double> share = batchShares(cells, run, ms);
                double framesSeconds = seconds;
                for (size_t k : run) framesSeconds -= ms[k].programMs / 1e3;
                framesSeconds = std::max(0.0, framesSeconds);
                // Frames of the same setting from every pipeline: they must agree (bit-identical
                // by design), which catches a silent wrong image at a limit (tiling, launch
                // splitting).
                std::map<std::string, size_t> bySetting;
                std::map<size_t, std::pair<std::string, double>> diff;  // cell -> (other, max |d|)
                for (size_t k : run) {
                    const Measurement& m = ms[k];
                    if (!m.ok || !cells[k].stopAfterFailure || m.image.rgb.empty()) continue;
                    auto [it, fresh] = bySetting.emplace(cells[k].settingKey(), k);
                    if (fresh) continue;
                    double d = maxDifference(ms[it->second].image, m.image);
                    diff[k] = {cells[it->second].pipeline, d};
                    diff[it->second] = {cells[k].pipeline, d};
                }
                std::lock_guard<std::mutex> hold(state.lock);
                for (size_t k : here) {
                    Measurement& m = ms[k];
                    nlohmann::json row;
                    if (!skipWhy[k].empty()) {
                        progress.skipped(k, skipWhy[k]);
                        ++summary.notRun;
                        row =
                            rowJson(config, cells[k], m, where, sceneInfo.at(c.scene), skipWhy[k]);
                        row["cell_index"] = k;
                        state.results[k] = {row, std::nullopt};
                        continue;
                    }
                    double build = m.programMs / 1e3, frames = 0;
                    for (size_t r = 0; r < run.size(); ++r)
                        if (run[r] == k) frames = share[r];
                    progress.finished(k, build + framesSeconds * frames, build, m, tag);
                    ++(m.ok ? summary.measured : summary.failed);
                    row = rowJson(config, cells[k], m, where, sceneInfo.at(c.scene));
                    row["cell_index"] = k;
                    if (m.ok && cells[k].stopAfterFailure && !m.image.rgb.empty()) {
                        row["image_nonfinite"] = nonFinitePixels(m.image);
                        if (row["image_nonfinite"].get<long long>() > 0)
                            std::fprintf(stderr, "    WARNING: %lld pixels are NaN or infinite\n",
                                         row["image_nonfinite"].get<long long>());
                    }
                    if (auto it = diff.find(k); it != diff.end()) {
                        row["image_compared_with"] = it->second.first;
                        row["image_max_diff"] = it->second.second;
                        if (it->second.second != 0)
                            std::fprintf(stderr,
                                         "    WARNING: %s and %s frames differ by up to %g\n",
                                         cells[k].pipeline.c_str(), it->second.first.c_str(),
                                         it->second.second);
                    }
                    if (cells[k].stopAfterFailure) {
                        if (!m.ok) {
                            stops.push_back(
                                {cells[k], std::string("error: ") + failureKindName(m.failure)});
                        } else if (cells[k].maxFrameS > 0 && m.wallMs > cells[k].maxFrameS * 1e3) {
                            char why[96];
                            std::snprintf(why, sizeof why,
                                          "a frame took %.1f s, over max-frame-s %g",
                                          m.wallMs / 1e3, cells[k].maxFrameS);
                            stops.push_back({cells[k], why});
                        }
                    }
                    Result& r = state.results[k];
                    r.row = std::move(row);
                    if (m.ok && cells[k].images) r.image = std::move(m.image);
                }
                emit(false);
            }
        }
    };
    // A worker that throws (the sink could not write, say) stops the others; the first error
    // is rethrown here once they have finished.
    auto guarded = [&](size_t w) {
        try {
            worker(w);
        } catch (...) {
            std::lock_guard<std::mutex> hold(state.lock);
            if (!state.error) state.error = std::current_exception();
            state.stop = true;
        }
    };
    if (contexts.size() == 1) {
        guarded(0);
    } else {
        std::vector<std::thread> threads;
        for (size_t w = 0; w < contexts.size(); ++w) threads.emplace_back(guarded, w);
        for (std::thread& t : threads) t.join();
    }
    emit(true);
    if (state.error) std::rethrow_exception(state.error);
    progress.done();
    summary.seconds = progress.elapsed();
    summary.meta["finished"] = utcNow();
    summary.meta["host_load_end"] = loadAverage();
    summary.meta["seconds"] = summary.seconds;
    summary.meta["complete"] = summary.complete;
    summary.meta["measured"] = summary.measured;
    summary.meta["failed"] = summary.failed;
    summary.meta["timed_out"] = summary.timedOut;
    summary.meta["not_run"] = summary.notRun;
    return summary;
}

}  // namespace rt::bench
