// rtlab sweep CONFIG — runs a named sweep (bench/sweeps/, format in bench/sweeps/README.md) on one
// device or several (--devices), or one share of it (--shard), scores the accuracy group against
// the converged CPU reference, and writes results/<device-slug>/<sweep>.{json,csv}, the five
// charts and README.md (the charts and readme commands of tools/rtlab_report). With --import
// DIR... it does the same for what `rtlab-bench --sweep` measured on other machines (continued
// runs and shards merged in cell order); --export-scenes makes the scene folder that rtlab-bench
// can read.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/sweep_accuracy.h"
#include "bench/measure.h"
#include "bench/pfm.h"
#include "bench/sweep_config.h"
#include "bench/sweep_runner.h"
#include "core/error.h"
#include "image/image_io.h"

namespace rt::cli {
namespace fs = std::filesystem;

namespace {

struct SweepArgs {
    std::string config, device, devices, shard, out, sceneDir, kernelDir, exportScenes;
    std::vector<std::string> importDirs;
    double timeLimit = 0;
    double cellTimeout = bench::kDefaultCellTimeoutS;
    bool noCharts = false, force = false;
} sweepArgs;

CLI::App* sweepCmd = nullptr;

std::string csvField(const nlohmann::json& v) {
    std::string s;
    if (v.is_null()) return "";
    if (v.is_string())
        s = v.get<std::string>();
    else if (v.is_boolean())
        s = v.get<bool>() ? "1" : "0";
    else if (v.is_number_float()) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.7g", v.get<double>());  // times to 0.1 us and better
        s = buf;
    } else
        s = v.dump();
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
    return q + "\"";
}

// One flat CSV row per result; kernel times get one column per kernel name.
// The keys of an object field over every row, in first-seen order (kernels, buffers, extras).
std::vector<std::string> keysOf(const nlohmann::json& rows, const char* field) {
    std::vector<std::string> keys;
    for (const auto& r : rows)
        if (r.contains(field))
            for (auto it = r[field].begin(); it != r[field].end(); ++it)
                if (std::find(keys.begin(), keys.end(), it.key()) == keys.end())
                    keys.push_back(it.key());
    return keys;
}

nlohmann::json field(const nlohmann::json& row, const char* object, const std::string& key) {
    return row.contains(object) && row[object].contains(key) ? row[object][key] : nlohmann::json();
}

void writeCsv(const nlohmann::json& rows, const fs::path& path) {
    const std::vector<std::string> kernels = keysOf(rows, "kernel_ms"),
                                   buffers = keysOf(rows, "buffers"),
                                   extras = keysOf(rows, "extras");
    const std::vector<std::string> head = {
        "sweep",         "groups",        "scene",          "pipeline", "width",
        "height",        "bounces",       "shadow_samples", "aa",       "accel",
        "layout",        "memory_budget", "adaptive",       "status",   "device_ms",
        "device_ms_min", "device_ms_max", "wall_ms"};
    const std::vector<std::string> tail = {
        "device_bytes", "tree_bytes", "private_bytes", "tree_nodes", "branching", "tiles",
        "mrays_per_s", "tree_used", "rmse", "mean_abs", "max_abs", "psnr_db", "warmup", "repeats",
        "robust_sphere", "watertight", "scaled_offset", "device", "platform", "driver", "commit",
        "error",
        // Added with the limits sweep (after the old columns, so old readers keep their places).
        "end", "failure", "skip_reason", "memory_tiles", "launches", "longest_launch_ms",
        "max_launch_ms", "frames", "image_max_diff", "image_nonfinite",
        // Added with the pipeline registry; then one column per buffer and per extra.
        "pipeline_title",
        // Added with the choice of secondary-ray offset: fixed, scaled or bound.
        "offset"};
    const char* counts[6] = {"objects", "spheres", "planes", "triangles", "meshes", "lights"};
    std::ofstream f(path);
    if (!f) throw Error(path.string() + ": cannot write");
    std::string line;
    for (const auto& h : head) line += h + ",";
    for (const auto& k : kernels) line += "k_" + k + "_ms,";
    for (int r = 0; r < RT_RAY_TYPES; ++r) line += std::string("rays_") + rayTypeName(r) + ",";
    for (const char* c : counts) line += std::string("scene_") + c + ",";
    for (const auto& t : tail) line += t + ",";
    for (const auto& b : buffers) line += "buffer_" + b + "_bytes,";
    for (const auto& x : extras) line += "extra_" + x + ",";
    line.pop_back();
    f << line << "\n";
    for (const auto& r : rows) {
        line.clear();
        auto get = [&](const std::string& k) { return r.contains(k) ? r[k] : nlohmann::json(); };
        for (const auto& h : head) {
            if (h == "groups") {
                std::string g;
                for (const auto& x : r["groups"])
                    g += (g.empty() ? "" : " ") + x.get<std::string>();
                line += csvField(g) + ",";
            } else {
                line += csvField(get(h)) + ",";
            }
        }
        for (const auto& k : kernels) line += csvField(field(r, "kernel_ms", k)) + ",";
        for (int x = 0; x < RT_RAY_TYPES; ++x)
            line += csvField(field(r, "rays", rayTypeName(x))) + ",";
        for (const char* c : counts) line += csvField(r["scene_info"][c]) + ",";
        for (const auto& t : tail) line += csvField(get(t)) + ",";
        for (const auto& b : buffers) line += csvField(field(r, "buffers", b)) + ",";
        for (const auto& x : extras) line += csvField(field(r, "extras", x)) + ",";
        line.pop_back();
        f << line << "\n";
    }
}

// The report package (tools/rtlab_report), run as a folder: python3 tools/rtlab_report COMMAND.
fs::path reportTool() {
    for (fs::path p : {fs::path("tools") / "rtlab_report",
                       fs::path(RTLAB_SOURCE_DIR) / "tools" / "rtlab_report"})
        if (fs::exists(p / "__main__.py")) return p;
    return {};
}

// Charts and README through Debian's Python (python3-matplotlib, scripts/setup); a missing
// Python is a warning, not a failed sweep: the data are written already.
void drawCharts(const fs::path& json) {
    fs::path tool = reportTool();
    if (tool.empty()) {
        std::fprintf(stderr, "rtlab sweep: tools/rtlab_report not found; no charts or README\n");
        return;
    }
    for (const char* command : {"charts", "readme"}) {
        std::string cmd =
            "/usr/bin/python3 '" + tool.string() + "' " + command + " '" + json.string() + "'";
        if (std::system(cmd.c_str()) != 0)
            std::fprintf(stderr,
                         "rtlab sweep: %s failed (is python3-matplotlib installed? run "
                         "scripts/setup)\n",
                         cmd.c_str());
    }
}

// rtlab-bench cannot decode PNG: a copy of the scene folder whose cubemap faces are .pfm, holding
// exactly the linear values readImage gives here.
int exportScenes(const fs::path& dest) {
    fs::path src =
        fs::exists("scenes") ? fs::path("scenes") : fs::path(RTLAB_SOURCE_DIR) / "scenes";
    fs::create_directories(dest);
    fs::copy(src, dest, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    int converted = 0;
    for (const auto& entry : fs::directory_iterator(dest)) {
        if (entry.path().extension() != ".json") continue;
        std::ifstream in(entry.path());
        nlohmann::json scene = nlohmann::json::parse(in, nullptr, true, true);
        if (!scene.contains("environment") || !scene["environment"].contains("cubemap")) continue;
        for (auto& face : scene["environment"]["cubemap"]) {
            fs::path file = face.get<std::string>();
            fs::path pfm = fs::path(file).replace_extension(".pfm");
            bench::writePfm(readImage(src / file), dest / pfm);
            face = pfm.generic_string();
            ++converted;
        }
        std::ofstream(entry.path()) << scene.dump(2) << "\n";
    }
    std::printf("exported %s to %s (%d cubemap faces as .pfm)\n", src.string().c_str(),
                dest.string().c_str(), converted);
    return 0;
}

nlohmann::json readJsonLines(const fs::path& path) {
    std::ifstream f(path);
    if (!f) throw Error(path.string() + ": cannot read");
    nlohmann::json rows = nlohmann::json::array();
    std::string line;
    for (int n = 1; std::getline(f, line); ++n) {
        if (line.empty()) continue;
        try {
            rows.push_back(nlohmann::json::parse(line));
        } catch (const nlohmann::json::exception&) {
            // The last line of a run killed at its limit may be cut off.
            std::fprintf(stderr, "rtlab sweep: %s:%d: unreadable row skipped\n",
                         path.string().c_str(), n);
        }
    }
    return rows;
}

// Rows in the sweep's cell order (cell_index): shards and devices measure out of order, and
// merged shards then read like a run on one machine. Rows without an index keep their place.
void sortByCell(nlohmann::json& rows, std::vector<PendingFrame>& frames) {
    for (const auto& r : rows)
        if (!r.contains("cell_index")) return;
    std::vector<size_t> order(rows.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) {
        return rows[x]["cell_index"].get<size_t>() < rows[y]["cell_index"].get<size_t>();
    });
    std::vector<size_t> placeOf(rows.size());
    nlohmann::json sorted = nlohmann::json::array();
    for (size_t i = 0; i < order.size(); ++i) {
        placeOf[order[i]] = i;
        sorted.push_back(std::move(rows[order[i]]));
    }
    rows = std::move(sorted);
    for (PendingFrame& f : frames) f.row = placeOf[f.row];
}

}  // namespace

void addSweep(CLI::App& app) {
    SweepArgs& a = sweepArgs;
    sweepCmd = app.add_subcommand(
        "sweep",
        "Run a named benchmark sweep and write results/<device>/ (CSV, JSON, charts, README)");
    std::string names;
    for (const auto& [name, what] : bench::listSweeps()) names += "\n  " + name + ": " + what;
    sweepCmd->add_option("config", a.config,
                         "Sweep file, or a name in bench/sweeps/ (format and purposes in "
                         "bench/sweeps/README.md; `rtlab sweeps` lists them):" +
                             names);
    sweepCmd->add_option("--device", a.device,
                         "OpenCL device: index or name substring [$RTLAB_DEVICE, else first GPU]");
    sweepCmd->add_option("--devices", a.devices,
                         "Run the cells on several devices at once, one context each: all (every "
                         "GPU) or indices and names separated by commas (0,1; a device named twice "
                         "gets two contexts); rows keep the sweep's cell order");
    sweepCmd->add_option("--shard", a.shard,
                         "Run only share i of N (i/N: work units u with u % N == i), e.g. one task "
                         "of a cluster array job; merge the shards with --import DIR0 DIR1 ...");
    sweepCmd->add_option("--out", a.out,
                         "Output folder [results/<device-slug>]; a folder that holds this sweep's "
                         "results already is refused unless --force is given");
    sweepCmd->add_flag("--force", a.force, "Overwrite this sweep's results in the output folder");
    sweepCmd
        ->add_option("--import", a.importDirs,
                     "Do not measure: score and chart what `rtlab-bench --sweep CONFIG --out DIR` "
                     "wrote to DIR on another machine; several folders: runs continued with "
                     "--resume, or the shards of --shard i/N, merged in cell order")
        ->take_all();
    sweepCmd->add_option("--time-limit", a.timeLimit,
                         "Stop before a cell that would end after this many seconds");
    sweepCmd
        ->add_option("--cell-timeout", a.cellTimeout,
                     "A cell (program builds included) that has not finished after this many "
                     "seconds fails with \"timeout\"; after a stuck compiler the sweep goes on "
                     "in a fresh context, after a stuck device it stops with the rows so far "
                     "written; the exit status is then 1. 0: no limit")
        ->check(CLI::Range(0.0, 1e7))
        ->capture_default_str();
    sweepCmd->add_option("--scene-dir", a.sceneDir, "Folder holding <scene>.json [scenes/]");
    sweepCmd->add_option("--kernel-dir", a.kernelDir, "Read kernel sources from this source tree");
    sweepCmd->add_flag("--no-charts", a.noCharts, "Write CSV and JSON only");
    sweepCmd->add_option(
        "--export-scenes", a.exportScenes,
        "Copy scenes/ to this folder with .pfm cubemap faces (for rtlab-bench) and exit");
}

int runSweepCommand() {
    SweepArgs& a = sweepArgs;
    if (!a.exportScenes.empty()) return exportScenes(a.exportScenes);
    if (a.config.empty())
        throw Error("sweep: name a sweep file (e.g. rtlab sweep bench/sweeps/quick)");
    bench::SweepConfig config = bench::loadSweep(bench::findSweep(a.config));

    nlohmann::json meta, rows = nlohmann::json::array();
    std::vector<PendingFrame> frames;
    int timedOut = 0;
    // Results already in the output folder are kept unless --force: checked before measuring.
    auto outputFolder = [&](const std::string& slug) {
        fs::path out = a.out.empty() ? fs::path("results") / slug : fs::path(a.out);
        fs::path json = out / (config.name + ".json");
        if (!a.force && fs::exists(json))
            throw Error("--out " + out.string() + ": holds " + config.name + " results already (" +
                        json.string() + "); --force overwrites them, or give another --out");
        return out;
    };
    fs::path out;
    std::map<std::string, bool> shardComplete;  // by --shard spec ("" for none)
    int shardCount = 0;
    if (!a.importDirs.empty()) {
        std::map<std::string, size_t> cellRow;
        for (const std::string& d : a.importDirs) {
            fs::path dir = d;
            std::ifstream m(dir / "sweep.json");
            if (!m)
                throw Error((dir / "sweep.json").string() +
                            ": cannot read (was it made by "
                            "rtlab-bench --sweep?)");
            nlohmann::json part = nlohmann::json::parse(m);
            if (part.value("sweep", "") != config.name)
                throw Error(dir.string() + " holds sweep '" + part.value("sweep", "") + "', not '" +
                            config.name + "'");
            // Shards (--shard i/N) are parts of one run: their cells add up, and the set is
            // complete once every shard's last part is. Parts of one shard continue each other.
            std::string shard = part.value("shard", "");
            auto [seenShard, firstOfShard] = shardComplete.emplace(shard, false);
            seenShard->second = part.value("complete", false);
            if (!shard.empty()) shardCount = std::stoi(shard.substr(shard.find('/') + 1));
            if (meta.is_null()) {
                meta = part;
                meta.erase("shard");
                out = outputFolder(meta.value("device_slug", "unknown-device"));
            } else if (firstOfShard) {
                for (const char* k :
                     {"measured", "failed", "not_run", "seconds", "cells", "skipped_as_done"})
                    meta[k] = meta.value(k, 0.0) + part.value(k, 0.0);
                meta["finished"] = std::max(meta.value("finished", ""), part.value("finished", ""));
                if (part.value("commit", "") != meta.value("commit", ""))
                    throw Error(dir.string() + " was measured at commit " +
                                part.value("commit", "") + ", the first folder at " +
                                meta.value("commit", ""));
            } else {
                // A continued run: its cells add to the first run's; the sums and the end move.
                for (const char* k : {"measured", "failed", "not_run", "seconds"})
                    meta[k] = meta.value(k, 0.0) + part.value(k, 0.0);
                meta["finished"] = part.value("finished", "");
                meta["complete"] = part.value("complete", false);
                if (part.value("commit", "") != meta.value("commit", ""))
                    throw Error(dir.string() + " was measured at commit " +
                                part.value("commit", "") + ", the first folder at " +
                                meta.value("commit", ""));
            }
            meta["imported_from"] =
                (meta.contains("imported_from") ? meta["imported_from"].get<std::string>() + " + "
                                                : "") +
                dir.string();
            for (auto& row : readJsonLines(dir / "rows.jsonl")) {
                // A cell measured again (it failed the first time) replaces its old row.
                size_t at = rows.size();
                std::string cell = bench::currentCellKey(row.value("cell", ""));
                auto it = cellRow.find(cell);
                if (it != cellRow.end() && !cell.empty()) {
                    at = it->second;
                    std::erase_if(frames, [&](const PendingFrame& f) { return f.row == at; });
                }
                if (row.contains("image")) {
                    fs::path image = dir / row["image"].get<std::string>();
                    if (fs::exists(image))
                        frames.push_back({at, bench::readPfm(image)});
                    else
                        std::fprintf(stderr, "rtlab sweep: %s missing; row not scored\n",
                                     image.string().c_str());
                    row.erase("image");
                }
                if (at == rows.size())
                    rows.push_back(row);
                else
                    rows[at] = row;
                cellRow[cell] = at;
            }
        }
    } else {
        bench::SweepRunOptions o;
        o.device = a.device;
        if (!a.devices.empty() && !a.device.empty())
            throw Error("sweep: --device and --devices: give one (--devices " + a.device +
                        " for one device)");
        o.devices = a.devices;
        if (!a.shard.empty()) o.shard = bench::parseShard(a.shard);
        o.sceneDir = a.sceneDir;
        o.readImage = readImage;
        o.sources = KernelSources(a.kernelDir.empty() && std::getenv("RTLAB_KERNEL_DIR")
                                      ? std::getenv("RTLAB_KERNEL_DIR")
                                      : a.kernelDir);
        o.timeLimitS = a.timeLimit;
        o.cellTimeoutS = a.cellTimeout;
        out = outputFolder(a.out.empty()
                               ? bench::deviceSlug(o.devices.empty()
                                                       ? selectDevice(o.device)
                                                       : bench::selectDevices(o.devices).front())
                               : "");
        bench::SweepSummary s =
            bench::runSweep(config, o, nullptr, [&](const nlohmann::json& row, const Image* image) {
                if (image) frames.push_back({rows.size(), *image});
                rows.push_back(row);
            });
        meta = s.meta;
        timedOut = s.timedOut;
    }
    if (!a.importDirs.empty()) {
        if (shardCount > 0) {
            nlohmann::json shards = nlohmann::json::array();
            bool complete = true;
            for (const auto& [shard, done] : shardComplete) {
                shards.push_back(shard);
                complete = complete && done;
            }
            meta["shards"] = shards;
            meta["complete"] = complete && int(shardComplete.size()) == shardCount;
            if (int(shardComplete.size()) != shardCount || shardComplete.count(""))
                std::fprintf(stderr,
                             "rtlab sweep: warning: %zu of %d shards imported; the set is "
                             "incomplete\n",
                             shardComplete.size(), shardCount);
        }
        sortByCell(rows, frames);
    }
    if (!frames.empty()) scoreFrames(rows, frames, config, a.sceneDir);

    fs::create_directories(out);
    fs::path json = out / (config.name + ".json");
    std::ofstream(json) << nlohmann::json{{"meta", meta}, {"rows", rows}}.dump(1) << "\n";
    writeCsv(rows, out / (config.name + ".csv"));
    std::printf("wrote %s and %s.csv (%zu rows)\n", json.string().c_str(),
                (out / config.name).string().c_str(), rows.size());
    if (!a.noCharts) drawCharts(json);
    if (timedOut) {
        std::fprintf(stderr, "rtlab sweep: %d cell(s) timed out (their rows say where)\n",
                     timedOut);
        return 1;
    }
    return 0;
}

}  // namespace rt::cli
