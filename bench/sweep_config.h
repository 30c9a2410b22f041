// rtlab bench — sweep files (bench/sweeps/*, format in bench/sweeps/README.md): named groups of
// cells, each group a Cartesian product of scenes x pipelines x sizes x bounce limits x shadow
// samples x AA x accel. Read by `rtlab sweep` and `rtlab-bench --sweep`; both run the same cells.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/pipeline.h"
#include "core/scene.h"
#include "pipelines/registry.h"

namespace rt::bench {

// One group of a sweep file. An empty list means "the scene's default".
struct SweepGroup {
    std::string name;  // "resolution", "bounces", "accel", "accuracy", or any other
    std::vector<std::string> scenes;
    std::vector<std::string> pipelines;
    std::vector<std::pair<int, int>> sizes;
    std::vector<int> bounces, shadowSamples, aa;
    std::vector<RenderOptions::Accel> accels;
    size_t memoryBudget = 0;
    bool adaptive = false;
    bool images = false;            // keep the frame for the accuracy comparison
    int repeats = -1, warmup = -1;  // -1: the sweep's
    int countRays = -1;             // -1: the sweep's, else 0 or 1
    double maxLaunchMs = 0;         // split frames so no launch runs past this (0: one launch)
    // The pipelines' own options given by the group's keys (PipelineInfo::options: the queue's
    // pool, for one); the pipelines that do not declare one ignore it.
    PipelineOptionValues pipelineOptions;
    // Once a pipeline fails at a setting (or a frame takes longer than maxFrameS), the group's
    // settings of that pipeline that are no smaller (size, bounce limit) are skipped.
    bool stopAfterFailure = false;
    double maxFrameS = 0;  // 0: no cap
};

struct SweepConfig {
    std::string name;  // file stem: "quick", "full"
    std::filesystem::path path;
    std::string text;       // the file as read, recorded with the results
    int repeats = 5;        // timed frames per cell; the median is reported
    int warmup = 2;         // untimed frames first (program build, allocation, caches)
    bool countRays = true;  // one extra untimed frame with device ray counters
    // The converged reference the accuracy group is compared against (CPU, double precision).
    int referenceBounces = 12, referenceShadowSamples = 64, referenceAa = 8;
    // cl-options: compiler options every program of the sweep is built with besides the host's
    // (a diagnostic's define, e.g. -DRT_PERSIST_PHASE_CLOCKS), as $RTLAB_CL_OPTIONS adds them;
    // runSweep puts them there for the run, after any the environment has.
    std::string clOptions;
    std::vector<SweepGroup> groups;
};

// Throws rt::Error "<file>:<line>: <reason>".
SweepConfig parseSweep(const std::string& text, const std::filesystem::path& path);
SweepConfig loadSweep(const std::filesystem::path& path);

// A sweep named by path, or by bare name under bench/sweeps/ of the source tree.
std::filesystem::path findSweep(const std::string& nameOrPath);

// The sweeps in bench/sweeps/ (of the working directory, else of the source tree), each with
// the first line of its header comment: {"quick", "a first look: ..."}.
std::vector<std::pair<std::string, std::string>> listSweeps();

// One measured cell: a scene, a pipeline and fully resolved render options.
struct Cell {
    std::string scene;
    std::string pipeline;  // a registered name
    RenderOptions options;
    std::vector<std::string> groups;  // every group that asked for this cell
    bool images = false;
    int repeats = 5, warmup = 2;
    int branching = 1;  // the scene's C, for cost estimates
    bool countRays = true;
    bool accelApplies = true;        // false when the scene has no spheres or triangles
    std::vector<int> groupIds;       // indices into SweepConfig::groups, parallel to `groups`
    bool stopAfterFailure = false;   // some group of this cell stops after a failure
    double maxFrameS = 0;            // the smallest cap of its groups (0: none)
    std::string key() const;         // identity, for de-duplication
    std::string settingKey() const;  // the same without the pipeline
    // Cells of one batch differ only in pipeline, accel and size: their frames are interleaved.
    std::string batchKey() const;
    std::string label() const;  // "cornell wave 1280x720 b4 s8 aa1 bv"
};

// A cell key as rows record it (Cell::key()), in today's form. Keys written while the
// megakernel's layout was a field of RenderOptions held it as a number after the accel field
// ("|0" tree, "|1" weighted) in every cell; today the layout is the megakernel's own option and
// shows, as the other declared options do, only when not at its default ("|Wweighted", in
// registration order among the option tags). A key already in today's form comes back unchanged.
// Whatever matches recorded rows against cells (--resume, merged result folders) reads the
// recorded keys through this.
std::string currentCellKey(const std::string& recordedKey);

// Expands the groups over the loaded scenes' defaults, merging duplicates (file order kept).
// sceneFor returns the loaded scene of a name.
std::vector<Cell> expandCells(const SweepConfig& config,
                              const std::function<const Scene&(const std::string&)>& sceneFor);

// Every scene name the sweep uses, in first-use order.
std::vector<std::string> sweepScenes(const SweepConfig& config);

// stop-after-failure: why `cell` is not worth running, given the cells that stopped before it
// (failed, or ran past max-frame-s), or "" to run it. A stopped cell rules out the cells of a
// group (with stop-after-failure) it shares, of the same pipeline and scene and every other
// setting alike, whose width, height and bounce limit are each at least its own.
struct Stop {
    Cell cell;
    std::string why;  // "error: ..." or "time: ..."
};
std::string skipReason(const SweepConfig& config, const Cell& cell, const std::vector<Stop>& stops);

}  // namespace rt::bench
