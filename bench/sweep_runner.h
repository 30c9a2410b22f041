// rtlab bench — running a sweep on one device or several: loads the scenes, expands the cells,
// measures each (bench/measure.h), shows a progress line with the cell and the time left, and
// hands every result row to a sink in cell order as soon as the cells before it are done, so
// that a run cut short keeps what it measured.
// `rtlab sweep` and `rtlab-bench --sweep` are two front ends of this one loop.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "bench/sweep_config.h"
#include "bench/sweep_schedule.h"
#include "core/kernel_sources.h"
#include "core/scene_loader.h"

namespace rt::bench {

struct SweepRunOptions {
    std::string device;  // --device spec (empty: $RTLAB_DEVICE, else first GPU)
    // --devices spec (bench/sweep_schedule.h): when set, one worker and context per device
    // take work units from a shared queue; rows still reach the sink in cell order.
    std::string devices;
    Shard shard;                     // --shard i/N: only this share of the work units
    std::filesystem::path sceneDir;  // <scene>.json lives here; empty: scenes/ of the checkout
    ImageReader readImage;           // for cubemap faces
    KernelSources sources;
    double timeLimitS = 0;  // stop before a cell that would end past this; 0 = none
    // A cell that has not finished after this many seconds (k cells measured interleaved: k
    // times as long) is recorded as failed with "timeout". When the OpenCL compiler was what
    // did not return, the sweep goes on in a fresh context; when the device or driver did, it
    // stops there with every row so far written (--resume then goes on past that cell).
    // 0 = no limit.
    double cellTimeoutS = 0;
    std::set<std::string> skip;  // Cell::key()s measured by an earlier run (--resume)
};

// row: one cell's results (settings, times, counters, device, commit); image: its frame when
// the cell keeps images (accuracy group), else null.
using RowSink = std::function<void(const nlohmann::json& row, const Image* image)>;

struct SweepSummary {
    nlohmann::json meta;  // sweep, config text, device, commit, settings, start and end time
    int cells = 0, measured = 0, failed = 0, skipped = 0;
    int notRun = 0;        // skipped by stop-after-failure (a row with status "skipped" each)
    int timedOut = 0;      // cells over the cell time limit (counted in `failed` too)
    bool complete = true;  // false when the time limit or a timeout on the device stopped it
    double seconds = 0;
};

// meta is handed to the sink's owner before the first cell through onStart (may be null).
SweepSummary runSweep(const SweepConfig& config, const SweepRunOptions& options,
                      const std::function<void(const nlohmann::json& meta)>& onStart,
                      const RowSink& sink);

// Where a scene named in a sweep lives: a path as given, else <dir>/<name>.json.
std::filesystem::path scenePath(const std::string& name, const std::filesystem::path& sceneDir);

// The file name a kept frame is stored under: "cornell-wave-320x180-b4-s8-aa2-bv.pfm".
std::string imageName(const nlohmann::json& row);

// The sweep's settings as recorded in meta (repeats, warm-up, reference, groups).
nlohmann::json sweepSettingsJson(const SweepConfig& config);

// "2m05s"
std::string formatDuration(double seconds);

// The default cell time limit: far above what any cell of the standard sweeps takes on a GPU,
// program builds included, and above the longest PoCL cells of the cpu and limits sweeps.
constexpr double kDefaultCellTimeoutS = 600;

// How a row's cell ended, for the limits sweep: "ran", "ran (tiled into K tiles)" (a global
// ray tree did not fit the device's max allocation or the memory budget in one piece),
// "error: <the message>" or "skipped".
std::string endState(const nlohmann::json& row);

// Row tiles the frame was split into because its memory did not fit in one piece (the
// max allocation or the memory budget), as the pipeline reported it ("extras": "memory_tiles");
// 1 for a pipeline that never tiles.
int memoryTiles(const nlohmann::json& row);

}  // namespace rt::bench
