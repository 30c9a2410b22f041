// rtlab — --persistent-schedule auto (persistent.h): the schedule a scene's traced warps call for,
// and trial frames where they cannot tell.
#include <cstdio>
#include <limits>

#include "core/error.h"
#include "persistent/persistent.h"

namespace rt {

// persistent.cpp's options.
const PipelineOption& persistScheduleOption();
std::vector<const PipelineOption*> persistSettingOptions();

namespace {

// The regrouped schedule's work-group: 256 lanes, or the most whose hits fit the device's local
// memory and work-group size, a power of two.
long long regroupLanes(const DeviceInfo& dev) {
    long long lanes = 256;
    while (lanes > 16 &&
           (size_t(lanes) > dev.maxWorkGroup || size_t(lanes) * kRegroupSlotBytes > dev.localMem))
        lanes /= 2;
    return lanes;
}

}  // namespace

bool PersistentPipeline::decide(TrialChoice& choice, const Scene& scene, const RenderOptions& base,
                                const std::vector<TrialCandidate>& candidates) {
    const FrameKey key(scene, base);
    if (choice.key && *choice.key == key) return false;
    const FrameStats frame = stats_;  // the schedule's extras and note, kept
    double best = std::numeric_limits<double>::infinity();
    std::optional<Error> refused;
    choice.chosen.clear();
    choice.trialsMs = nlohmann::json::object();
    choice.refused = nlohmann::json::object();
    for (const TrialCandidate& candidate : candidates) {
        double ms = std::numeric_limits<double>::infinity();
        try {
            for (int i = 0; i < 2; ++i) {  // the first may pay for building the program
                stats_ = {};
                renderRun(scene, base, candidate.run);
                ms = std::min(ms, stats_.deviceMs);
            }
            choice.trialsMs[candidate.name] = ms;
        } catch (const Error& e) {
            choice.trialsMs[candidate.name] = nullptr;
            choice.refused[candidate.name] = e.what();
            refused = e;
            continue;
        }
        if (ms < best) best = ms, choice.chosen = candidate.name;
    }
    stats_ = frame;
    if (choice.chosen.empty()) throw *refused;
    choice.key = key;
    return true;
}

PersistentPipeline::Run PersistentPipeline::chooseSchedule(const Scene& scene,
                                                           const RenderOptions& o) {
    for (const PipelineOption* option : persistSettingOptions())
        if (!option->isDefault(o.pipelineOptions))
            throw Error("--persistent-schedule auto chooses " + option->flag() +
                            " itself; leave it out or use another --persistent-schedule",
                        FailureKind::InvalidOption);
    const LaneEstimate& estimate = estimates_.get(scene, o);
    const PersistChoice choice = choosePersistentSchedule(estimate);
    stats_.extras["persist_busy_lanes"] = estimate.busyLanes;
    stats_.extras["persist_objects_per_warp"] = estimate.objectsPerWarp;
    stats_.extras["persist_predict_ms"] = estimates_.lastMs();
    stats_.extras["persist_schedule"] = choice.name();
    stats_.note = "persistent schedule: " + std::string(choice.name()) + ": " + choice.reason;
    if (!choice.regroup) {
        // Which order keeps a work-group's patch in cache depends on the scene's layout on
        // screen, which the traced warps do not see: on the H200, 16x8 strips (the megakernel's
        // own work-groups) ran spheres 4-7% faster than 4x16, and cornell, mesh and envmap 4-8%
        // slower.
        const Run nested{&persistSchedule("nested")}, wide{&persistSchedule("nested-16x8")};
        const bool decided = decide(order_, scene, o, {{"4x16", nested}, {"16x8", wide}});
        stats_.extras["persist_tile"] = order_.chosen;
        stats_.extras["persist_tile_trials_ms"] = order_.trialsMs;
        stats_.extras["persist_tile_decided"] = decided;  // this frame timed the orders
        stats_.note += "; " + order_.chosen + " strips, the faster of two trial frames each";
        return order_.chosen == "16x8" ? wide : nested;
    }
    // Two regrouped work-groups of 256 lanes a compute unit at 128 registers, or the bounce loop
    // at its defaults. Both keep a warp's lanes busy where trees disagree; which costs less a step
    // depends on the shading: on the H200 the bounce loop was 2-5% faster than the regrouped
    // loop on four walls of six and 4-7% slower on the two whose noise patterns the regrouped
    // loop sorts.
    const Run regrouped{&persistSchedule("regrouped"), regroupLanes(cl_.device()), 2, 128};
    const Run bounce{&persistSchedule("bounce")};
    const bool decided = decide(loop_, scene, o, {{"regrouped", regrouped}, {"bounce", bounce}});
    if (loop_.chosen != "bounce") bounce_.reset();  // the trial's scratch is not kept
    stats_.extras["persist_loop"] = loop_.chosen;
    stats_.extras["persist_loop_trials_ms"] = loop_.trialsMs;
    stats_.extras["persist_loop_decided"] = decided;  // this frame timed the loops
    if (!loop_.refused.empty()) stats_.extras["persist_loop_refused"] = loop_.refused;
    stats_.note += "; the " + loop_.chosen + " loop, the faster of two trial frames each";
    return loop_.chosen == "bounce" ? bounce : regrouped;
}

}  // namespace rt
