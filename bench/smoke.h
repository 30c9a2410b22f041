// rtlab bench — the smoke check that runs before any GPU result is called done (`rtlab-bench
// --smoke`, scripts/gpu-smoke): every scene with every registered pipeline in each of its
// variants (the megakernel's layouts) and every acceleration structure at each size, one frame
// each under the cell time limit, and one line per cell: PASS when the frame was rendered, every
// pixel is finite and it agrees with the megakernel's frame (tree layout, the scene's own
// structure) as the accel tests require of two structures; FAIL with the reason otherwise. A stuck
// program build or device fails its cell, and the check goes on where the driver allows
// (bench/sweep_runner.h says when).
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/sweep_schedule.h"
#include "core/kernel_sources.h"
#include "core/scene_loader.h"

namespace rt::bench {

struct SmokeOptions {
    std::vector<std::string> scenes;  // names in sceneDir (or paths)
    // Scenes checked at the first size with the BVH alone, every pipeline and variant: the SPD
    // (about 10,000 primitives each, scenes/spd), where every structure at every size would
    // multiply the check's time for little more coverage.
    std::vector<std::string> spotScenes;
    std::vector<std::string> sizes;      // "WxH"
    std::vector<std::string> pipelines;  // registered device pipelines; variants come with them
    std::vector<std::string> accels;     // names (core/accel.h); each applies where it differs
    std::filesystem::path sceneDir;
    ImageReader readImage;
    KernelSources sources;
    std::string device;
    Shard shard;  // this process's share of the (scene, structure) units
    double cellTimeoutS = 0;
};

// The defaults of --smoke: every standard scene and the divergence scene, 160x90 and 1920x1080,
// every registered device pipeline, every structure; the seven SPD scenes at 160x90 with the BVH.
SmokeOptions defaultSmokeOptions();

struct SmokeSummary {
    int cells = 0, passed = 0, failed = 0;
    bool stopped = false;  // a device that did not return stopped the check (cells left unrun)
};

// Prints "PASS|FAIL  <scene> <size> <pipeline> <variant> <accel>  <ms>  <detail>" to out, one
// line per cell as it ends (<variant>: tree or weighted for the megakernel, "-" for a pipeline
// without variants), in a fixed order (units in shard order, then size, then variant).
SmokeSummary runSmoke(const SmokeOptions& options, std::FILE* out);

}  // namespace rt::bench
