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
    // own pipeline declares, which tell its variants apart in charts and tables; under
    // "option_labels" those of them the cell set away from their defaults, as the registry words
    // them ("nested loop"), which the charts name a variant by.
    auto json = [](const OptionValue& v) {
        const long long* n = std::get_if<long long>(&v);
        return n ? nlohmann::json(*n) : nlohmann::json(std::get<std::string>(v));
    };
    for (const PipelineOption* opt : pipelineRegistry().options())
        row[opt->field()] = json(opt->value(o.pipelineOptions));
    nlohmann::json own = nlohmann::json::object(), labels = nlohmann::json::object();
    for (const PipelineOption& opt : pipelineInfo(c.pipeline).options) {
        own[opt.name] = json(opt.value(o.pipelineOptions));
        if (!opt.isDefault(o.pipelineOptions)) labels[opt.name] = opt.describe(o.pipelineOptions);
    }
    row["options"] = own;
    row["option_labels"] = labels;
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
             {{"pipeline", "oracle"},
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

// ---- Planning: what this run measures ----

// The sweep's scenes, loaded once. Shared, because a measurement that overruns the cell time
// limit keeps its scene while the sweep goes on.
struct SweepScenes {
    std::map<std::string, std::shared_ptr<const Scene>> scenes;
    std::map<std::string, nlohmann::json> info;  // sceneJson() of each, for meta and rows
};

SweepScenes loadSweepScenes(const SweepConfig& config, const SweepRunOptions& options) {
    SweepScenes s;
    for (const std::string& name : sweepScenes(config)) {
        s.scenes.emplace(name, std::make_shared<const Scene>(loadScene(
                                   scenePath(name, options.sceneDir), options.readImage)));
        s.info[name] = sceneJson(*s.scenes.at(name));
    }
    return s;
}

// The whole sweep's cells, and the share of them this run measures: the work units of its
// shard, less the cells an earlier run measured (--resume). Cell and unit indices are those of
// the whole sweep, whatever shard and resume leave of it, so they are the same on every machine
// and the shards' rows merge by them.
struct SweepPlan {
    std::vector<Cell> cells;
    std::vector<WorkUnit> units;  // this shard's, in sweep order
    std::vector<size_t> order;    // the cells to run, in cell order
    int skippedAsDone = 0;        // cells of this shard that --resume skips
};

SweepPlan planSweep(const SweepConfig& config, const SweepRunOptions& options,
                    const SweepScenes& scenes) {
    SweepPlan plan;
    plan.cells = expandCells(
        config, [&](const std::string& n) -> const Scene& { return *scenes.scenes.at(n); });
    std::vector<char> inShard(plan.cells.size(), 0);
    std::vector<WorkUnit> all = workUnits(plan.cells);
    for (size_t u = 0; u < all.size(); ++u) {
        if (int(u % size_t(options.shard.count)) != options.shard.index) continue;
        for (auto [i, j] : all[u].batches)
            for (size_t k = i; k < j; ++k) inShard[k] = 1;
        plan.units.push_back(std::move(all[u]));
    }
    for (size_t k = 0; k < plan.cells.size(); ++k) {
        if (!inShard[k]) continue;
        if (options.skip.count(plan.cells[k].key()))
            ++plan.skippedAsDone;
        else
            plan.order.push_back(k);
    }
    return plan;
}

// The set's meta before the first cell: the sweep file, its settings and scenes, the device
// (of the first context; every device with --devices), the shard and the cell time limit.
nlohmann::json sweepMeta(const SweepConfig& config, const SweepRunOptions& options,
                         const SweepPlan& plan, const SweepScenes& scenes,
                         const std::vector<DeviceInfo>& devices) {
    nlohmann::json meta = {{"sweep", config.name},
                           {"config_file", config.path.string()},
                           {"config", config.text},
                           {"settings", sweepSettingsJson(config)},
                           {"scenes", scenes.info},
                           {"started", utcNow()},
                           {"host_load_start", loadAverage()},
                           {"cells", plan.order.size()},
                           {"cell_timeout_s", options.cellTimeoutS},
                           {"skipped_as_done", plan.skippedAsDone}};
    meta.update(deviceJson(devices.front()));
    if (!options.shard.whole()) {
        meta["shard"] = options.shard.str();
        meta["sweep_cells"] = plan.cells.size();
    }
    if (devices.size() > 1) {
        nlohmann::json list = nlohmann::json::array();
        for (const DeviceInfo& d : devices) {
            list.push_back(deviceJson(d));
            list.back()["device_index"] = d.index;
        }
        meta["devices"] = list;
    }
    return meta;
}

// The run's first line on stderr: the cell count, the shard, where it runs and the commit;
// before it, a warning when the devices of one run differ (their rows do not compare).
void announceSweep(const SweepConfig& config, const SweepRunOptions& options, const SweepPlan& plan,
                   const std::vector<DeviceInfo>& devices) {
    std::string on = devices.front().label();
    if (devices.size() > 1) {
        on = std::to_string(devices.size()) + " contexts:";
        for (size_t w = 0; w < devices.size(); ++w) {
            on += (w ? ", d" : " d") + std::to_string(w) + " = " + devices[w].label();
            if (devices[w].name != devices.front().name)
                std::fprintf(stderr,
                             "sweep %s: warning: the devices differ (%s, %s); each row "
                             "names its own\n",
                             config.name.c_str(), devices.front().name.c_str(),
                             devices[w].name.c_str());
        }
    }
    std::fprintf(stderr, "sweep %s: %zu cells%s on %s, commit %s\n", config.name.c_str(),
                 plan.order.size(),
                 options.shard.whole() ? "" : (" (shard " + options.shard.str() + ")").c_str(),
                 on.c_str(), RTLAB_COMMIT);
}

// ---- Running: the workers and what they share ----

// One cell's outcome, waiting for its turn in the output.
struct Result {
    nlohmann::json row;
    std::optional<Image> image;
};

// One worker: a device's context (replaced after a stuck program build), what its rows say of
// the device, and the tag its progress lines carry when several devices share the sweep.
struct Worker {
    std::shared_ptr<ClContext> cl;
    nlohmann::json where;
    std::string tag;
};

// A sweep in progress. Each worker takes the next work unit from the shared queue and runs its
// batches in order: it starts a batch (under the time limit), measures it (under the cell time
// limit), and records its rows; rows go to the sink in cell order as soon as every earlier cell
// is done. The members below lock_ are guarded by it, and so are progress and summary.
class SweepRun {
  public:
    SweepRun(const SweepConfig& config, const SweepRunOptions& options, const SweepPlan& plan,
             const SweepScenes& scenes, Progress& progress, SweepSummary& summary,
             const RowSink& sink)
        : config_(config),
          options_(options),
          plan_(plan),
          scenes_(scenes),
          progress_(progress),
          summary_(summary),
          sink_(sink) {}

    // Runs work units until none is left or the sweep stops. A worker that throws (the sink
    // could not write, say) stops the others; the first error is kept for finish().
    void work(Worker self) {
        try {
            for (;;) {
                size_t u;
                {
                    std::lock_guard<std::mutex> hold(lock_);
                    if (stop_ || nextUnit_ == plan_.units.size()) return;
                    u = nextUnit_++;
                }
                if (!runUnit(self, plan_.units[u])) return;
            }
        } catch (...) {
            std::lock_guard<std::mutex> hold(lock_);
            if (!error_) error_ = std::current_exception();
            stop_ = true;
        }
    }

    // After the workers: the rows still held back go out (past cells that never ran), and a
    // worker's error is rethrown.
    void finish() {
        emit(true);
        if (error_) std::rethrow_exception(error_);
    }

  private:
    // A unit's batches in order. stop-after-failure is decided within a unit (a scene's limits
    // batches are one unit), from the cells of it that failed or ran past max-frame-s. False
    // when the sweep stopped before one of its batches.
    bool runUnit(Worker& self, const WorkUnit& unit) {
        std::vector<Stop> stops;
        for (auto [i, j] : unit.batches) {
            std::vector<size_t> here;  // the batch's cells less those --resume skips
            for (size_t k = i; k < j; ++k)
                if (!options_.skip.count(plan_.cells[k].key())) here.push_back(k);
            if (here.empty()) continue;
            // stop-after-failure: cells no smaller than one that stopped are recorded, not run.
            std::vector<size_t> run;
            std::map<size_t, std::string> skipWhy;
            for (size_t k : here) {
                if (plan_.cells[k].stopAfterFailure)
                    skipWhy[k] = skipReason(config_, plan_.cells[k], stops);
                if (skipWhy[k].empty()) run.push_back(k);
            }
            if (!run.empty() && !startBatch(run, self.tag)) return false;
            std::map<size_t, Measurement> ms;
            double seconds = run.empty() ? 0 : measureBatch(self, plan_.cells[i], run, ms);
            recordBatch(self, plan_.cells[i], here, run, skipWhy, ms, seconds, stops);
        }
        return true;
    }

    // --time-limit: a batch that would end past it is not started, and the sweep stops there
    // (the first batch always starts). Otherwise its cells show as started. False: stopped.
    bool startBatch(const std::vector<size_t>& run, const std::string& tag) {
        std::lock_guard<std::mutex> hold(lock_);
        if (stop_) return false;
        double predicted = 0;
        for (size_t k : run) predicted += progress_.estimate(k);
        if (options_.timeLimitS > 0 && started_ &&
            progress_.elapsed() + predicted > options_.timeLimitS) {
            std::fprintf(stderr,
                         "\nsweep %s: stopping before %s, the time limit of "
                         "%s would pass\n",
                         config_.name.c_str(), plan_.cells[run.front()].label().c_str(),
                         formatDuration(options_.timeLimitS).c_str());
            summary_.complete = false;
            stop_ = true;
            return false;
        }
        started_ = true;
        progress_.starting(run, tag);
        return true;
    }

    // Measures the batch's cells with their frames interleaved (first: the batch's first cell,
    // whose scene and frame counts the batch shares), under the cell time limit times the
    // number of cells. Fills ms by cell index; returns the batch's seconds.
    double measureBatch(Worker& self, const Cell& first, const std::vector<size_t>& run,
                        std::map<size_t, Measurement>& ms) {
        std::vector<Variant> variants;
        bool keep = false;
        double cap = 0;
        for (size_t k : run) {
            const Cell& c = plan_.cells[k];
            variants.push_back({c.pipeline, c.options});
            // The limits cells keep their frames: the pipelines' images must agree.
            keep = keep || c.images || c.stopAfterFailure;
            if (c.maxFrameS > 0) cap = cap > 0 ? std::min(cap, c.maxFrameS) : c.maxFrameS;
        }
        auto t0 = std::chrono::steady_clock::now();
        // A limits batch gets a context of its own: drivers keep memory per context (NVIDIA
        // reserves private memory for the largest kernel it ran), so a wavefront cell after the
        // megakernel's deepest cells could fail where it runs in a new process.
        std::shared_ptr<ClContext> ctx =
            first.stopAfterFailure
                ? std::make_shared<ClContext>(self.cl->device(), options_.sources)
                : self.cl;
        std::shared_ptr<const Scene> scene = scenes_.scenes.at(first.scene);
        const double limit = options_.cellTimeoutS * double(run.size());
        auto got = withinSeconds(limit, [=, warmup = first.warmup, repeats = first.repeats,
                                         countRays = first.countRays] {
            return measureCells(*ctx, *scene, variants, warmup, repeats, countRays, keep, cap);
        });
        double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (got) {
            for (size_t r = 0; r < run.size(); ++r) ms[run[r]] = std::move((*got)[r]);
        } else {
            timedOut(self, *ctx, ctx == self.cl, run, limit, ms);
        }
        return seconds;
    }

    // A batch past the cell time limit: each of its cells fails with "timeout", naming what was
    // stuck. The stuck thread keeps ctx and the scene; this worker never touches ctx again. A
    // stuck compiler runs nothing on the device, so the worker goes on in a new context; a
    // stuck device or driver leaves a state that later timings could not be trusted in, so the
    // sweep stops.
    void timedOut(Worker& self, const ClContext& ctx, bool workersContext,
                  const std::vector<size_t>& run, double limit, std::map<size_t, Measurement>& ms) {
        const std::string compiling = ctx.building();
        char head[160];
        std::snprintf(
            head, sizeof head,
            "did not finish within %g s (cell time "
            "limit %g s%s): ",
            limit, options_.cellTimeoutS,
            run.size() > 1
                ? (" x " + std::to_string(run.size()) + " cells measured together").c_str()
                : "");
        std::string why = head + (compiling.empty() ? std::string("the device or its driver "
                                                                  "did not return")
                                                    : "the OpenCL compiler did not finish "
                                                      "building " +
                                                          compiling);
        for (size_t k : run) {
            Measurement& m = ms[k];
            m.error = why;
            m.failure = FailureKind::Timeout;
        }
        std::lock_guard<std::mutex> hold(lock_);
        summary_.timedOut += int(run.size());
        if (!compiling.empty() && workersContext) {
            self.cl = std::make_shared<ClContext>(self.cl->device(), options_.sources);
        } else if (compiling.empty()) {
            const std::string label = plan_.cells[run.front()].label();
            std::fprintf(stderr,
                         "\nsweep %s: %s timed out on the device; "
                         "stopping (rows so far are written; --resume "
                         "goes on past it)\n",
                         config_.name.c_str(), label.c_str());
            summary_.complete = false;
            summary_.meta["stopped_by"] = "timeout: " + label;
            stop_ = true;
        }
    }

    // The rows of a batch's cells, with their progress lines, in cell order: here are those
    // --resume left, run those of them that were measured, skipWhy says why the others were not
    // (stop-after-failure). Each measured cell gets its share of the batch's time for the
    // estimate of the time left; cells of stop-after-failure groups that failed or ran past
    // max-frame-s go to stops. Then whatever rows are due go to the sink.
    void recordBatch(const Worker& self, const Cell& first, const std::vector<size_t>& here,
                     const std::vector<size_t>& run, std::map<size_t, std::string>& skipWhy,
                     std::map<size_t, Measurement>& ms, double seconds, std::vector<Stop>& stops) {
        // The batch's time less its program builds, shared out over its cells.
        const std::vector<double> share = batchShares(plan_.cells, run, ms);
        double framesSeconds = seconds;
        for (size_t k : run) framesSeconds -= ms[k].programMs / 1e3;
        framesSeconds = std::max(0.0, framesSeconds);
        const auto diff = frameAgreement(run, ms);
        const nlohmann::json& sceneInfo = scenes_.info.at(first.scene);
        std::lock_guard<std::mutex> hold(lock_);
        for (size_t k : here) {
            const Cell& cell = plan_.cells[k];
            Measurement& m = ms[k];
            if (!skipWhy[k].empty()) {
                progress_.skipped(k, skipWhy[k]);
                ++summary_.notRun;
                nlohmann::json row = rowJson(config_, cell, m, self.where, sceneInfo, skipWhy[k]);
                row["cell_index"] = k;
                results_[k] = {row, std::nullopt};
                continue;
            }
            double build = m.programMs / 1e3, frames = 0;
            for (size_t r = 0; r < run.size(); ++r)
                if (run[r] == k) frames = share[r];
            progress_.finished(k, build + framesSeconds * frames, build, m, self.tag);
            ++(m.ok ? summary_.measured : summary_.failed);
            nlohmann::json row = rowJson(config_, cell, m, self.where, sceneInfo);
            row["cell_index"] = k;
            if (m.ok && cell.stopAfterFailure && !m.image.rgb.empty()) {
                row["image_nonfinite"] = nonFinitePixels(m.image);
                if (row["image_nonfinite"].get<long long>() > 0)
                    std::fprintf(stderr, "    WARNING: %lld pixels are NaN or infinite\n",
                                 row["image_nonfinite"].get<long long>());
            }
            if (auto it = diff.find(k); it != diff.end()) {
                row["image_compared_with"] = it->second.first;
                row["image_max_diff"] = it->second.second;
                if (it->second.second != 0)
                    std::fprintf(stderr, "    WARNING: %s and %s frames differ by up to %g\n",
                                 cell.pipeline.c_str(), it->second.first.c_str(),
                                 it->second.second);
            }
            if (cell.stopAfterFailure) {
                if (!m.ok) {
                    stops.push_back({cell, std::string("error: ") + failureKindName(m.failure)});
                } else if (cell.maxFrameS > 0 && m.wallMs > cell.maxFrameS * 1e3) {
                    char why[96];
                    std::snprintf(why, sizeof why, "a frame took %.1f s, over max-frame-s %g",
                                  m.wallMs / 1e3, cell.maxFrameS);
                    stops.push_back({cell, why});
                }
            }
            Result& r = results_[k];
            r.row = std::move(row);
            if (m.ok && cell.images) r.image = std::move(m.image);
        }
        emit(false);
    }

    // Frames of the same setting from every pipeline of a limits batch must agree (bit-identical
    // by design), which catches a silent wrong image at a limit (tiling, launch splitting).
    // By cell: the pipeline it was compared with and the largest |difference|.
    std::map<size_t, std::pair<std::string, double>> frameAgreement(
        const std::vector<size_t>& run, std::map<size_t, Measurement>& ms) const {
        std::map<std::string, size_t> bySetting;
        std::map<size_t, std::pair<std::string, double>> diff;
        for (size_t k : run) {
            const Measurement& m = ms[k];
            if (!m.ok || !plan_.cells[k].stopAfterFailure || m.image.rgb.empty()) continue;
            auto [it, fresh] = bySetting.emplace(plan_.cells[k].settingKey(), k);
            if (fresh) continue;
            double d = maxDifference(ms[it->second].image, m.image);
            diff[k] = {plan_.cells[it->second].pipeline, d};
            diff[it->second] = {plan_.cells[k].pipeline, d};
        }
        return diff;
    }

    // Hands finished rows to the sink in cell order, as far as every earlier cell is done
    // (all: also past cells that never ran, at the end). Callers hold the lock, or run alone.
    void emit(bool all) {
        for (; emitted_ < plan_.order.size(); ++emitted_) {
            auto it = results_.find(plan_.order[emitted_]);
            if (it == results_.end()) {
                if (all) continue;
                return;
            }
            sink_(it->second.row, it->second.image ? &*it->second.image : nullptr);
            results_.erase(it);
        }
    }

    const SweepConfig& config_;
    const SweepRunOptions& options_;
    const SweepPlan& plan_;
    const SweepScenes& scenes_;
    Progress& progress_;
    SweepSummary& summary_;
    const RowSink& sink_;

    std::mutex lock_;
    size_t nextUnit_ = 0;
    bool started_ = false, stop_ = false;  // a batch began; the time limit (or an error) stops all
    std::exception_ptr error_;
    std::map<size_t, Result> results_;  // by cell index, until every earlier cell is out
    size_t emitted_ = 0;                // plan_.order[0, emitted_) went to the sink
};

// What the set's meta says at the end: when it finished, the host's load, and the counts.
void finishMeta(SweepSummary& summary) {
    summary.meta["finished"] = utcNow();
    summary.meta["host_load_end"] = loadAverage();
    summary.meta["seconds"] = summary.seconds;
    summary.meta["complete"] = summary.complete;
    summary.meta["measured"] = summary.measured;
    summary.meta["failed"] = summary.failed;
    summary.meta["timed_out"] = summary.timedOut;
    summary.meta["not_run"] = summary.notRun;
}

}  // namespace

namespace {

// The sweep's cl-options in $RTLAB_CL_OPTIONS (after any the environment has) while it runs, so
// that every program build takes them, every row records them, and the cache keeps those
// builds apart; the environment as it was afterwards.
class ClOptionsForTheRun {
  public:
    explicit ClOptionsForTheRun(const std::string& options) {
        const char* env = std::getenv("RTLAB_CL_OPTIONS");
        if (env) before_ = env;
        had_ = env != nullptr;
        if (options.empty()) return;
        set_ = true;
        const std::string both = before_.empty() ? options : before_ + " " + options;
        setenv("RTLAB_CL_OPTIONS", both.c_str(), 1);
    }
    ~ClOptionsForTheRun() {
        if (!set_) return;
        if (had_)
            setenv("RTLAB_CL_OPTIONS", before_.c_str(), 1);
        else
            unsetenv("RTLAB_CL_OPTIONS");
    }
    ClOptionsForTheRun(const ClOptionsForTheRun&) = delete;
    ClOptionsForTheRun& operator=(const ClOptionsForTheRun&) = delete;

  private:
    std::string before_;
    bool had_ = false, set_ = false;
};

}  // namespace

SweepSummary runSweep(const SweepConfig& config, const SweepRunOptions& options,
                      const std::function<void(const nlohmann::json&)>& onStart,
                      const RowSink& sink) {
    const ClOptionsForTheRun clOptions(config.clOptions);
    const SweepScenes scenes = loadSweepScenes(config, options);
    const SweepPlan plan = planSweep(config, options, scenes);
    std::vector<DeviceInfo> devices = options.devices.empty()
                                          ? std::vector<DeviceInfo>{selectDevice(options.device)}
                                          : selectDevices(options.devices);
    std::vector<Worker> workers;
    for (const DeviceInfo& d : devices) {
        Worker w{std::make_shared<ClContext>(d, options.sources), {}, ""};
        w.where = deviceJson(w.cl->device());
        w.where["device_index"] = w.cl->device().index;
        if (devices.size() > 1) w.tag = " on d" + std::to_string(workers.size());
        workers.push_back(std::move(w));
    }
    SweepSummary summary;
    summary.cells = int(plan.order.size());
    summary.skipped = plan.skippedAsDone;
    summary.meta = sweepMeta(config, options, plan, scenes, devices);
    announceSweep(config, options, plan, devices);
    if (onStart) onStart(summary.meta);

    Progress progress(plan.cells, plan.order, int(devices.size()));
    SweepRun run(config, options, plan, scenes, progress, summary, sink);
    if (workers.size() == 1) {
        run.work(workers[0]);
    } else {
        std::vector<std::thread> threads;
        for (const Worker& w : workers) threads.emplace_back([&run, w] { run.work(w); });
        for (std::thread& t : threads) t.join();
    }
    run.finish();
    progress.done();
    summary.seconds = progress.elapsed();
    finishMeta(summary);
    return summary;
}

}  // namespace rt::bench
