// rtlab bench — the sweep loop (see sweep_runner.h).
#include "bench/sweep_runner.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <optional>

#include "bench/measure.h"
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

// A rough relative cost of a cell, scaled per scene by what was measured so far, for the ETA.
double cellCost(const Cell& c) {
    const RenderOptions& o = c.options;
    double frames = c.warmup + c.repeats + (c.countRays ? 1 : 0);
    // Rays grow about with the bounce limit; a pipeline with a global tree (one that tiles it)
    // also walks every slot of that tree.
    double work = 1.0 + o.bounces;
    if (pipelineInfo(c.pipeline).supports.tiling)
        work += double(treeNodeCount(c.branching, o.bounces)) / 16;
    return double(o.width) * o.height * o.aa * o.aa * work * frames;
}

class Progress {
public:
    explicit Progress(const std::vector<Cell>& cells)
        : cells_(cells), tty_(isatty(fileno(stderr))),
          start_(std::chrono::steady_clock::now()) {
        // Cells that stop-after-failure may skip are counted in: the ETA is then a bound.
        for (const Cell& c : cells) mayStop_ = mayStop_ || c.stopAfterFailure;
    }
    double elapsed() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }
    // Seconds the cells from i on should take, from the rate measured on the same scene and
    // pipeline, else on the scene, else overall: pipelines differ by far more than the cost
    // model's terms (the quick sweep's "ETA 2s" came before a 21 s wavefront cell).
    double remaining(size_t i) const {
        double overall = doneCost_ > 0 ? spent_ / doneCost_ : 0;
        double eta = 0;
        for (size_t j = i; j < cells_.size(); ++j) {
            double rate = overall;
            if (auto it = rate_.find(cells_[j].scene + "|" + cells_[j].pipeline); it != rate_.end())
                rate = it->second.first / it->second.second;
            else if (auto s = rate_.find(cells_[j].scene); s != rate_.end())
                rate = s->second.first / s->second.second;
            eta += rate * cellCost(cells_[j]);
        }
        return eta;
    }
    // The time left as shown: nothing until two cells were measured (one cell's rate, stretched
    // over a whole sweep, said "ETA <= 7h13m" for a 3-minute run), and a bound ("<=") where
    // stop-after-failure may skip cells.
    std::string eta(size_t i) const {
        if (measured_ < 2) return "estimating";
        return std::string(mayStop_ ? "<= " : "") + formatDuration(remaining(i));
    }
    double predict(size_t i, size_t j) const { return remaining(i) - remaining(j); }
    void starting(size_t i, size_t j) {
        if (!tty_) return;
        std::string what = cells_[i].label();
        if (j > i + 1) what += " (+" + std::to_string(j - i - 1) + " interleaved)";
        std::fprintf(stderr, "\r\033[K[%zu/%zu] %s ... | elapsed %s, ETA %s", i + 1, cells_.size(),
                     what.c_str(), formatDuration(elapsed()).c_str(), eta(i).c_str());
        std::fflush(stderr);
    }
    void skipped(size_t i, const std::string& why) {
        const Cell& c = cells_[i];
        std::fprintf(stderr, "%s[%zu/%zu] %s: skipped | elapsed %s\n    %s\n", tty_ ? "\r\033[K" : "",
                     i + 1, cells_.size(), c.label().c_str(), formatDuration(elapsed()).c_str(),
                     why.c_str());
        std::fflush(stderr);
    }
    void finished(size_t i, double seconds, const Measurement& m) {
        const Cell& c = cells_[i];
        double cost = cellCost(c);
        spent_ += seconds;
        doneCost_ += cost;
        for (const std::string& key : {c.scene + "|" + c.pipeline, c.scene}) {
            auto& r = rate_[key];
            r.first += seconds;
            r.second += cost;
        }
        ++measured_;
        char result[96];
        if (m.ok)
            std::snprintf(result, sizeof result, "%.3f ms", m.deviceMs);
        else
            std::snprintf(result, sizeof result, "failed");
        std::fprintf(stderr, "%s[%zu/%zu] %s: %s | elapsed %s, ETA %s%s", tty_ ? "\r\033[K" : "",
                     i + 1, cells_.size(), c.label().c_str(), result,
                     formatDuration(elapsed()).c_str(), eta(i + 1).c_str(), tty_ ? "" : "\n");
        if (!m.ok) std::fprintf(stderr, "%s    %s\n", tty_ ? "\n" : "", m.error.c_str());
        std::fflush(stderr);
    }
    void done() {
        if (tty_) std::fprintf(stderr, "\n");
    }

private:
    const std::vector<Cell>& cells_;
    bool tty_, mayStop_ = false;
    std::chrono::steady_clock::time_point start_;
    double spent_ = 0, doneCost_ = 0;
    int measured_ = 0;
    // Seconds and model cost measured per "scene|pipeline" and per scene.
    std::map<std::string, std::pair<double, double>> rate_;
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
        {"width", o.width},
        {"height", o.height},
        {"bounces", o.bounces},
        {"shadow_samples", o.shadowSamples},
        {"aa", o.aa},
        {"accel", c.accelApplies ? accelName(o.accel) : "-"},
        {"layout", o.layout == RenderOptions::Layout::Tree ? "tree" : "weighted"},
        {"memory_budget", o.memoryBudget},
        {"adaptive", o.adaptiveAa},
        {"max_launch_ms", o.maxLaunchMs},
        {"robust_sphere", o.robustSphere},
        {"watertight", o.watertight},
        {"scaled_offset", o.offset != RenderOptions::Offset::Fixed},  // old column: not fixed
        {"offset", offsetName(o.offset)},
        {"warmup", c.warmup},
        {"repeats", c.repeats},
        {"status", m.ok ? "ok" : skipped.empty() ? "error" : "skipped"},
        {"error", m.error},
    };
    if (c.stopAfterFailure) row["stop_after_failure"] = true;
    if (c.maxFrameS > 0) row["max_frame_s"] = c.maxFrameS;
    if (!skipped.empty()) row["skip_reason"] = skipped;
    // The kind is the one the error was thrown with (rt::Error's FailureKind), never read from
    // the message; a cell that failed without one is "other".
    FailureKind failure = !skipped.empty() ? FailureKind::Skipped
                          : m.ok           ? FailureKind::None
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
                    {"accel_build_ms", m.accelBuildMs}});
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

// The largest |difference| of two frames of one size (NaN in both at one place counts as equal,
// in one only as infinite), or -1 when the sizes differ.
double maxDifference(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) return -1;
    double worst = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        float x = a.rgb[i], y = b.rgb[i];
        if (std::isnan(x) || std::isnan(y)) {
            if (std::isnan(x) != std::isnan(y)) worst = INFINITY;
            continue;
        }
        worst = std::max(worst, x == y ? 0.0 : std::fabs(double(x) - double(y)));
    }
    return worst;
}

// Pixels with a channel that is NaN or infinite: never right, whatever the scene.
long long nonFinitePixels(const Image& image) {
    long long bad = 0;
    for (size_t i = 0; i + 2 < image.rgb.size(); i += 3)
        if (!std::isfinite(image.rgb[i]) || !std::isfinite(image.rgb[i + 1]) ||
            !std::isfinite(image.rgb[i + 2]))
            ++bad;
    return bad;
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
    if (p.has_extension()) return p;
    if (!sceneDir.empty()) return sceneDir / (name + ".json");
    if (fs::exists(fs::path("scenes") / (name + ".json"))) return fs::path("scenes") / (name + ".json");
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
    if (row.at("layout") != "tree") name += "-" + row.at("layout").get<std::string>();
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
            {"reference", {{"pipeline", "cpu"},
                           {"bounces", c.referenceBounces},
                           {"shadow_samples", c.referenceShadowSamples},
                           {"aa", c.referenceAa}}},
            {"groups", groups},
            {"timing", "device time = sum of the frame's kernels by OpenCL profiling events; "
                       "median of `repeats` frames after `warmup` untimed ones; rays counted "
                       "in one further untimed frame"}};
}

SweepSummary runSweep(const SweepConfig& config, const SweepRunOptions& options,
                      const std::function<void(const nlohmann::json&)>& onStart,
                      const RowSink& sink) {
    std::map<std::string, Scene> scenes;
    std::map<std::string, nlohmann::json> sceneInfo;
    for (const std::string& name : sweepScenes(config)) {
        scenes.emplace(name, loadScene(scenePath(name, options.sceneDir), options.readImage));
        sceneInfo[name] = sceneJson(scenes.at(name));
    }
    std::vector<Cell> cells =
        expandCells(config, [&](const std::string& n) -> const Scene& { return scenes.at(n); });
    size_t before = cells.size();
    std::erase_if(cells, [&](const Cell& c) { return options.skip.count(c.key()) > 0; });

    ClContext cl(selectDevice(options.device), options.sources);
    nlohmann::json device = deviceJson(cl.device());
    SweepSummary summary;
    summary.cells = int(cells.size());
    summary.skipped = int(before - cells.size());
    summary.meta = {{"sweep", config.name},
                    {"config_file", config.path.string()},
                    {"config", config.text},
                    {"settings", sweepSettingsJson(config)},
                    {"scenes", sceneInfo},
                    {"started", utcNow()},
                    {"host_load_start", loadAverage()},
                    {"cells", cells.size()},
                    {"skipped_as_done", summary.skipped}};
    summary.meta.update(device);
    std::fprintf(stderr, "sweep %s: %zu cells on %s, commit %s\n", config.name.c_str(), cells.size(),
                 cl.device().label().c_str(), RTLAB_COMMIT);
    if (onStart) onStart(summary.meta);

    Progress progress(cells);
    std::vector<Stop> stops;  // cells that failed or ran past max-frame-s (stop-after-failure)
    for (size_t i = 0; i < cells.size();) {
        // Adjacent cells that differ only in pipeline, accel or size (expandCells puts a group's
        // pipelines and accels innermost) are measured together, their frames interleaved, so
        // that wave/mega, accel/none and resolution ratios compare frames taken moments apart.
        size_t j = i + 1;
        while (j < cells.size() && cells[j].batchKey() == cells[i].batchKey()) ++j;
        // stop-after-failure: cells no smaller than one that stopped are recorded, not run.
        std::vector<size_t> run;
        std::vector<std::string> skipWhy(j - i);
        for (size_t k = i; k < j; ++k) {
            if (cells[k].stopAfterFailure) skipWhy[k - i] = skipReason(config, cells[k], stops);
            if (skipWhy[k - i].empty()) run.push_back(k);
        }
        if (!run.empty() && options.timeLimitS > 0 && i > 0 &&
            progress.elapsed() + progress.predict(i, j) > options.timeLimitS) {
            std::fprintf(stderr, "\nsweep %s: stopping before cell %zu of %zu, the time limit of %s "
                                 "would pass\n",
                         config.name.c_str(), i + 1, cells.size(),
                         formatDuration(options.timeLimitS).c_str());
            summary.complete = false;
            break;
        }
        const Cell& c = cells[i];
        std::vector<Measurement> ms(j - i);
        double seconds = 0;
        if (!run.empty()) {
            std::vector<Variant> variants;
            bool keep = false;
            double cap = 0;
            for (size_t k : run) {
                variants.push_back({cells[k].pipeline, cells[k].options});
                // The limits cells keep their frames: the pipelines' images must agree.
                keep = keep || cells[k].images || cells[k].stopAfterFailure;
                if (cells[k].maxFrameS > 0) cap = cap > 0 ? std::min(cap, cells[k].maxFrameS)
                                                          : cells[k].maxFrameS;
            }
            progress.starting(run.front(), run.back() + 1);
            auto t0 = std::chrono::steady_clock::now();
            // A limits batch gets a context of its own: drivers keep memory per context (NVIDIA
            // reserves private memory for the largest kernel it ran), and on the H100 that made
            // a wavefront cell fail after the megakernel's B=11 cells, yet run in a new process.
            std::optional<ClContext> own;
            if (c.stopAfterFailure) own.emplace(cl.device(), options.sources);
            std::vector<Measurement> got = measureCells(own ? *own : cl, scenes.at(c.scene), variants,
                                                        c.warmup, c.repeats, c.countRays, keep, cap);
            seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            for (size_t r = 0; r < run.size(); ++r) ms[run[r] - i] = std::move(got[r]);
        }
        double batchCost = 0;
        for (size_t k : run) batchCost += cellCost(cells[k]);
        // Frames of the same setting from every pipeline: they must agree (bit-identical by
        // design), which catches a silent wrong image at a limit (tiling, launch splitting).
        std::map<std::string, size_t> bySetting;
        std::map<size_t, std::pair<std::string, double>> diff;  // cell -> (other pipeline, max |d|)
        for (size_t k : run) {
            const Measurement& m = ms[k - i];
            if (!m.ok || !cells[k].stopAfterFailure || m.image.rgb.empty()) continue;
            auto [it, fresh] = bySetting.emplace(cells[k].settingKey(), k);
            if (fresh) continue;
            double d = maxDifference(ms[it->second - i].image, m.image);
            diff[k] = {cells[it->second].pipeline, d};
            diff[it->second] = {cells[k].pipeline, d};
        }
        for (size_t k = i; k < j; ++k) {
            const Measurement& m = ms[k - i];
            nlohmann::json row;
            if (!skipWhy[k - i].empty()) {
                progress.skipped(k, skipWhy[k - i]);
                ++summary.notRun;
                row = rowJson(config, cells[k], m, device, sceneInfo.at(c.scene), skipWhy[k - i]);
                sink(row, nullptr);
                continue;
            }
            // The batch's time, shared out by the cost model (a 4K cell outweighs a 640x360 one).
            progress.finished(k, seconds * cellCost(cells[k]) / batchCost, m);
            ++(m.ok ? summary.measured : summary.failed);
            row = rowJson(config, cells[k], m, device, sceneInfo.at(c.scene));
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
                    std::fprintf(stderr, "    WARNING: %s and %s frames differ by up to %g\n",
                                 cells[k].pipeline.c_str(), it->second.first.c_str(),
                                 it->second.second);
            }
            if (cells[k].stopAfterFailure) {
                if (!m.ok) {
                    stops.push_back({cells[k], std::string("error: ") + failureKindName(m.failure)});
                } else if (cells[k].maxFrameS > 0 && m.wallMs > cells[k].maxFrameS * 1e3) {
                    char why[96];
                    std::snprintf(why, sizeof why, "a frame took %.1f s, over max-frame-s %g",
                                  m.wallMs / 1e3, cells[k].maxFrameS);
                    stops.push_back({cells[k], why});
                }
            }
            sink(row, m.ok && cells[k].images ? &m.image : nullptr);
        }
        i = j;
    }
    progress.done();
    summary.seconds = progress.elapsed();
    summary.meta["finished"] = utcNow();
    summary.meta["host_load_end"] = loadAverage();
    summary.meta["seconds"] = summary.seconds;
    summary.meta["complete"] = summary.complete;
    summary.meta["measured"] = summary.measured;
    summary.meta["failed"] = summary.failed;
    summary.meta["not_run"] = summary.notRun;
    return summary;
}

}  // namespace rt::bench
