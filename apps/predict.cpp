// rtlab predict: which design a scene favours on a GPU, from the busy lanes of a sample of warps
// traced on the CPU (auto/predict.h), before any pipeline runs.
#include "auto/predict.h"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.h"
#include "apps/options.h"
#include "auto/persist_choice.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "image/image_io.h"

namespace rt::cli {
namespace {

CLI::App* predictCmd = nullptr;

struct PredictArgs {
    std::vector<std::string> scenes;
    std::string size;
    std::optional<int> bounces, aa;
    int warps = 2048;
    double threshold = kQueueBelowLanes;
    bool json = false, shading = false;
} args;

}  // namespace

void addPredict(CLI::App& app) {
    PredictArgs& a = args;
    predictCmd = app.add_subcommand(
        "predict",
        "Say which design should win on a GPU, before any runs: traces the ray trees of a sample\n"
        "of warps (16x2 pixels) on the CPU, without shading, and counts how many of a warp's 32\n"
        "lanes would be busy a step in a megakernel that gives each work-item a whole tree; also\n"
        "names the schedule --persistent-schedule auto would take (persist: regrouped or nested)");
    predictCmd->add_option("scenes", a.scenes, "Scene files (.json or .nff) or models")->required();
    predictCmd->add_option("--size", a.size, "Image size WxH (default: the scene's)");
    predictCmd->add_option("--bounces", a.bounces, "Bounce limit B (default: the scene's)")
        ->check(CLI::Range(0, 64));
    predictCmd->add_option("--aa", a.aa, "AA grid n (n x n samples a pixel; default: the scene's)")
        ->check(CLI::Range(1, 16));
    predictCmd->add_option("--warps", a.warps, "Warps traced, chosen at random with a fixed seed")
        ->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    predictCmd
        ->add_option("--threshold", a.threshold,
                     "Busy lanes of 32 below which the queue wavefront is predicted")
        ->check(CLI::Range(0.0, 32.0))
        ->capture_default_str();
    predictCmd->add_flag("--json", a.json, "One JSON object a scene on stdout instead of a table");
    predictCmd->add_flag(
        "--shading", a.shading,
        "Also count the shading keys (a procedural pattern, or plain, mirror, glass, a miss) the\n"
        "lanes of a warp step meet, in three orders of the same rays: the megakernel's (each lane\n"
        "its own tree), the bounce loop's lists (32 consecutive rays of one bounce), and those\n"
        "lists sorted by key (--persistent-schedule bounce-staged); 1 is one key's code;\n"
        "and the lanes of 32 that cast shadow rays in a step, inline and in a shadow pass");
}

bool predictParsed() { return predictCmd && predictCmd->parsed(); }

int runPredict() {
    const PredictArgs& a = args;
    int width = 0, height = 0;
    if (!a.size.empty()) parseSize(a.size, width, height);  // a bad --size before any scene
    bool header = !a.json;
    for (const std::string& file : a.scenes) {
        Scene scene = loadScene(file, readImage);
        RenderOptions o = scene.defaults;
        if (width > 0) o.width = width, o.height = height;
        if (a.bounces) o.bounces = *a.bounces;
        if (a.aa) o.aa = *a.aa;
        const LaneEstimate e = estimateBusyLanes(scene, o, a.warps);
        const Prediction p = predictDesign(e, a.threshold);
        // What --pipeline persist --persistent-schedule auto would render with (its own rule).
        const PersistChoice persist = choosePersistentSchedule(e);
        const char* schedule = persist.name();
        const std::optional<ShadingEstimate> shading =
            a.shading ? std::optional(estimateShadingKeys(scene, o, a.warps)) : std::nullopt;
        if (a.json) {
            nlohmann::json j = {
                {"scene", file},
                {"name", scene.name},
                {"width", o.width},
                {"height", o.height},
                {"bounces", o.bounces},
                {"aa", o.aa},
                {"warps", e.warps},
                {"lanes", e.lanes},
                {"busy_lanes", e.busyLanes},
                {"rays_per_pixel", e.raysPerPixel},
                {"largest_tree", e.largestTree},
                {"objects_per_warp", e.objectsPerWarp},
                {"objects", scene.spheres.size() + scene.planes.size() + scene.triangles.size()},
                {"predicted", p.design},
                {"threshold", a.threshold},
                {"reason", p.reason},
                {"persist_schedule", schedule},
                {"persist_reason", persist.reason},
                {"commit", RTLAB_COMMIT}};
            if (shading)
                j["shading_keys"] = {{"megakernel", shading->megakernel},
                                     {"bounce", shading->bounce},
                                     {"bounce_sorted", shading->sorted},
                                     {"batches", shading->batches},
                                     {"shadow_lanes_megakernel", shading->shadowMegakernel},
                                     {"shadow_lanes_bounce_inline", shading->shadowInline},
                                     {"shadow_lanes_bounce_pass", shading->shadowPass}};
            std::printf("%s\n", j.dump().c_str());
        } else {
            if (std::exchange(header, false))  // after the first scene loads, not before an error
                std::printf("%-40s %10s %10s %8s %9s %9s %10s  %s\n", "scene", "size", "busy/32",
                            "rays/px", "largest", "obj/warp", "persist", "predicted");
            std::printf("%-40s %10s %10.1f %8.2f %9d %9.1f %10s  %s\n", scene.name.c_str(),
                        (std::to_string(o.width) + "x" + std::to_string(o.height)).c_str(),
                        e.busyLanes, e.raysPerPixel, e.largestTree, e.objectsPerWarp, schedule,
                        p.reason.c_str());
            if (shading)
                std::printf(
                    "%-40s shading keys a warp step: megakernel %.2f, bounce loop %.2f, "
                    "sorted %.2f; lanes casting shadow rays: megakernel %.1f, bounce "
                    "loop %.1f, shadow pass %.1f\n",
                    "", shading->megakernel, shading->bounce, shading->sorted,
                    shading->shadowMegakernel, shading->shadowInline, shading->shadowPass);
        }
        std::fflush(stdout);
    }
    return 0;
}

}  // namespace rt::cli
