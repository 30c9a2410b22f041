// rtlab — the persistent megakernel's host driver (persistent.h).
#include "persistent/persistent.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.h"
#include "core/pipeline_registry.h"
#include "megakernel/megakernel.h"
#include "megakernel/megakernel_options.h"

namespace rt {

namespace {

const PipelineOption& groupsOption() {
    static const PipelineOption o{
        .name = "persistent-groups",
        .type = PipelineOption::Type::Integer,
        .help =
            "Persistent megakernel: work-groups per compute unit, 1..64; they take pixels "
            "from a counter until the frame is done [4]",
        .defaultValue = 4ll,
        .min = 1,
        .max = 64,
        .sweepKey = "persistent-groups",
        .cellTag = "G",
        .label = "{} groups per unit",
    };
    return o;
}

const PipelineOption& refillOption() {
    static const PipelineOption o{
        .name = "persistent-refill",
        .type = PipelineOption::Type::Integer,
        .help =
            "Persistent megakernel on NVIDIA: a warp's lanes without a pixel wait until N of "
            "them are idle (or all), then take neighbouring pixels together, 1..32; other "
            "devices take a pixel per work-item at once [1]",
        .defaultValue = 1ll,
        .min = 1,
        .max = 32,
        .sweepKey = "persistent-refill",
        .cellTag = "F",
        .label = "refill at {} idle lanes",
    };
    return o;
}

// The megakernel's register cap, for this pipeline's own program.
const PipelineOption& registersOption() {
    static const PipelineOption o =
        registerCapOption("persistent-max-registers", "Persistent megakernel",
                          " (raise --persistent-groups to fill them); where none is asked, a "
                          "build whose --persistent-lanes would not share the registers of a "
                          "multiprocessor is capped so that they do (128 at 512 lanes)",
                          "J");
    return o;
}

// The flat loop over rays, a loop over pixels around the megakernel's loop over rays, the flat
// loop in warp lockstep, or a work-group's batch of pixels traced bounce by bounce.
enum class PersistLoop { Flat, Nested, Lockstep, Bounce };  // loopOption()'s choices, in order

const PipelineOption& loopOption() {
    static const PipelineOption o{
        .name = "persistent-loop",
        .type = PipelineOption::Type::Choice,
        .help =
            "Persistent megakernel: flat (one loop over rays; a lane takes a pixel when its tree "
            "ends), nested (a loop over pixels around the megakernel's loop over rays; a "
            "work-group takes a pixel a lane once all its lanes are done), lockstep (the flat "
            "loop with a warp's 32 lanes starting every step together, NVIDIA; elsewhere the "
            "flat loop) or bounce (a work-group traces a batch of --persistent-batch pixels "
            "bounce by bounce, each bounce's rays compacted in global memory, a wavefront inside "
            "the launch); nested and lockstep do not regroup [flat]",
        .defaultValue = "flat",
        .choices = {"flat", "nested", "lockstep", "bounce"},
        .sweepKey = "persistent-loop",
        .cellTag = "L",
        .label = "{} loop",
    };
    return o;
}

// The pixels a work-group of the bounce loop takes together and traces bounce by bounce.
const PipelineOption& batchOption() {
    static const PipelineOption o{
        .name = "persistent-batch",
        .type = PipelineOption::Type::Integer,
        .help =
            "Persistent megakernel, --persistent-loop bounce (or --persistent-schedule auto, "
            "where it tries the bounce loop): pixels a work-group takes together and traces "
            "bounce by bounce, 16..65536; more keeps its later bounces' lanes busier and needs "
            "more scratch memory [1024]",
        .defaultValue = 1024ll,
        .min = 16,
        .max = 65536,
        .sweepKey = "persistent-batch",
        .cellTag = "U",
        .label = "batches of {} pixels",
    };
    return o;
}

// Where the bounce loop casts its shadow rays: each lane right after its own trace, or in a pass
// of their own over each bounce's hits.
enum class PersistShadows { Inline, Pass };  // shadowsOption()'s choices, in order

const PipelineOption& shadowsOption() {
    static const PipelineOption o{
        .name = "persistent-shadows",
        .type = PipelineOption::Type::Choice,
        .help =
            "Persistent megakernel, --persistent-loop bounce (or --persistent-schedule auto, "
            "where it tries the bounce loop): inline (a lane casts its hit's "
            "shadow rays right after tracing it) or pass (each bounce's closest hits first, then "
            "the shadow rays of the hits in a pass of their own, as the queue's shadow kernel "
            "casts them); same image [inline]",
        .defaultValue = "inline",
        .choices = {"inline", "pass"},
        .sweepKey = "persistent-shadows",
        .cellTag = "V",
        .label = "shadow rays {}",
    };
    return o;
}

// The order pixels are handed out in (persistent.cl, Persistent_PixelOf): strips W columns wide
// and H rows tall, row by row inside a strip, so that the 32 pixels a warp takes together are a
// W x (32 / W) block and the ones it takes next lie below them.
const PipelineOption& tileOption() {
    static const PipelineOption o{
        .name = "persistent-tile",
        .type = PipelineOption::Type::Choice,
        .help =
            "Persistent megakernel: the order pixels are taken in, strips WxH (W columns, H "
            "rows) taken row by row, a warp's 32 pixels a W-wide block; 16x8 hands out the "
            "megakernel's own work-groups (warps of 16x2) [4x16]",
        .defaultValue = "4x16",
        .choices = {"4x16", "8x4", "4x8", "8x16", "4x32", "8x32", "16x8"},
        .sweepKey = "persistent-tile",
        .cellTag = "T",
        .label = "{} strips",
    };
    return o;
}

// Work-items per work-group; 0 takes the device's default below.
const PipelineOption& laneOption() {
    static const PipelineOption o{
        .name = "persistent-lanes",
        .type = PipelineOption::Type::Integer,
        .help =
            "Persistent megakernel: work-items per work-group, 16..1024, at most what the "
            "device takes (and, regrouped, what its local memory holds): the lanes that "
            "--persistent-regroup sorts hits among, or that the nested loop hands pixels to "
            "together [128 on a GPU, 512 in the bounce loop; 64 elsewhere]",
        .defaultValue = 0ll,
        .min = 16,
        .max = 1024,
        .sweepKey = "persistent-lanes",
        .cellTag = "N",
        .label = "{} lanes a group",
    };
    return o;
}

// Whether a work-group sorts its hits before shading them (persistent.cl,
// Persistent_RenderRegrouped), and by what.
enum class PersistRegroup { Off, Pattern, Material };  // regroupOption()'s choices, in order

const PipelineOption& regroupOption() {
    static const PipelineOption o{
        .name = "persistent-regroup",
        .type = PipelineOption::Type::Choice,
        .help =
            "Persistent megakernel: off; pattern: each step, a work-group sorts its hits by "
            "procedural pattern in local memory and each lane shades the next hit of that "
            "order, so that a warp runs one pattern's code at a time (the bounce loop: each "
            "bounce's hits, in global memory); material: by pattern, and hits without one by "
            "class (plain, mirror, glass); same image [off]",
        .defaultValue = "off",
        .choices = {"off", "pattern", "material"},
        .sweepKey = "persistent-regroup",
        .cellTag = "O",
        .label = "regroup by {}",
    };
    return o;
}

// Whether the flags above set the schedule, or the predicted busy lanes choose it.
enum class PersistScheduleChoice { Flags, Auto };  // scheduleOption()'s choices, in order

const PipelineOption& scheduleOption() {
    static const PipelineOption o{
        .name = "persistent-schedule",
        .type = PipelineOption::Type::Choice,
        .help =
            [] {
                char rule[96];
                std::snprintf(rule, sizeof rule,
                              "below %.1f busy lanes of 32 or from %.1f objects a warp",
                              kRegroupBelowLanes, kRegroupFromObjects);
                return "Persistent megakernel: flags (the schedule the other --persistent-* flags "
                       "set) or auto (warps traced on the CPU, as `rtlab predict` does, choose: " +
                       std::string(rule) +
                       ", two work-groups of 256 lanes a compute unit at most 128 registers, "
                       "regrouped by pattern, or the bounce loop at its defaults (with "
                       "--persistent-batch and --persistent-shadows where given); otherwise the "
                       "nested loop, in 4x16 or 16x8 strips; where there are two, whichever two "
                       "trial frames each find faster) [flags]";
            }(),
        .defaultValue = "flags",
        .choices = {"flags", "auto"},
        .sweepKey = "persistent-schedule",
        .cellTag = "H",
        .label = "{} schedule",
    };
    return o;
}

// Bytes of local memory a regrouped lane keeps: persistent.cl's RegroupSlot, a union of a hit
// (Node, 48, and Pending, 64 with its float3 alignment) and a shading result (a float3 term, two
// Pendings and a child mask, 148, padded to 160).
constexpr size_t kRegroupSlotBytes = 160;

// A work-group size the device cannot run: one line naming the flag, before any build.
void checkLanes(const DeviceInfo& dev, size_t local, bool regroup) {
    const std::string flag = "--persistent-lanes " + std::to_string(local) + ": ";
    if (local > dev.maxWorkGroup)
        throw Error(flag + dev.name + " runs at most " + std::to_string(dev.maxWorkGroup) +
                        " work-items a work-group",
                    FailureKind::InvalidOption);
    if (regroup && local * kRegroupSlotBytes > dev.localMem)
        throw Error(flag + "regrouped, a work-group keeps " + std::to_string(kRegroupSlotBytes) +
                        " bytes of local memory a lane, and " + dev.name + " has " +
                        std::to_string(dev.localMem) + " a work-group",
                    FailureKind::InvalidOption);
}

// The options --persistent-schedule auto sets itself.
const std::vector<const PipelineOption*>& scheduledOptions() {
    static const std::vector<const PipelineOption*> options{
        &groupsOption(), &refillOption(),    &regroupOption(), &laneOption(),
        &loopOption(),   &registersOption(), &tileOption()};
    return options;
}

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

long long persistentRegisterCap(const DeviceInfo& dev, size_t lanes, long long asked) {
    if (dev.registersPerGroup == 0 || lanes == 0) return asked;
    // NVIDIA gives a warp its registers in units of 256, 8 a lane, up to 255 a lane.
    constexpr long long kMost = 255, kUnit = 8;
    const auto warpLanes = static_cast<long long>((lanes + 31) / 32 * 32);
    const long long fits = std::min(kMost, dev.registersPerGroup / warpLanes / kUnit * kUnit);
    if (asked > fits) {
        const std::string group = std::to_string(lanes) + " work-items a work-group";
        throw Error("--persistent-max-registers " + std::to_string(asked) + ": " + group +
                        " (--persistent-lanes) share " + dev.name + "'s " +
                        std::to_string(dev.registersPerGroup) + " registers, at most " +
                        std::to_string(fits) + " each; lower either flag",
                    FailureKind::InvalidOption);
    }
    return asked != 0 || fits == kMost ? asked : fits;
}

PersistSchedule choosePersistentSchedule(const LaneEstimate& e) {
    char lanes[80], objects[80];
    std::snprintf(lanes, sizeof lanes, "%.1f busy lanes of %d predicted", e.busyLanes, e.lanes);
    std::snprintf(objects, sizeof objects, "%.1f objects a warp", e.objectsPerWarp);
    if (e.busyLanes < kRegroupBelowLanes) {
        char why[64];
        std::snprintf(why, sizeof why, " (below %.1f)", kRegroupBelowLanes);
        return {true, std::string(lanes) + why +
                          ": trees disagree, so work-groups regroup their hits by pattern"};
    }
    if (e.objectsPerWarp >= kRegroupFromObjects) {
        char why[64];
        std::snprintf(why, sizeof why, " (at least %.1f)", kRegroupFromObjects);
        return {true, std::string(objects) + why +
                          ": a warp shades several patterns, so work-groups regroup their "
                          "hits by pattern"};
    }
    return {false, std::string(lanes) + " and " + objects +
                       ": trees and patterns agree, so the nested loop keeps a work-group on "
                       "neighbours"};
}

void setPersistentScheduleAuto(RenderOptions& o) {
    scheduleOption().set(o.pipelineOptions, std::string("auto"));
}

size_t PersistentPipeline::workItems(const DeviceInfo& device, const RenderOptions& o,
                                     size_t local) {
    const size_t groups = size_t(groupsOption().integer(o.pipelineOptions));
    return std::max<cl_uint>(device.computeUnits, 1) * groups * local;
}

RenderOptions PersistentPipeline::chooseSchedule(const Scene& scene, const RenderOptions& o) {
    for (const PipelineOption* option : scheduledOptions())
        if (!option->isDefault(o.pipelineOptions))
            throw Error("--persistent-schedule auto chooses " + option->flag() +
                            " itself; leave it out or use --persistent-schedule flags",
                        FailureKind::InvalidOption);
    const LaneEstimate& estimate = estimates_.get(scene, o);
    const PersistSchedule schedule = choosePersistentSchedule(estimate);
    // --persistent-batch and --persistent-shadows are the bounce loop's (chooseLoop's other
    // candidate): the regrouped and nested loops run without them.
    RenderOptions out = o;
    for (const PipelineOption* option : {&batchOption(), &shadowsOption()})
        out.pipelineOptions.reset(option->name);
    if (schedule.regroup) {
        regroupOption().set(out.pipelineOptions, std::string("pattern"));
        laneOption().set(out.pipelineOptions, regroupLanes(cl_.device()));
        groupsOption().set(out.pipelineOptions, 2ll);
        registersOption().set(out.pipelineOptions, 128ll);
    } else {
        loopOption().set(out.pipelineOptions, std::string("nested"));
    }
    stats_.extras["persist_busy_lanes"] = estimate.busyLanes;
    stats_.extras["persist_objects_per_warp"] = estimate.objectsPerWarp;
    stats_.extras["persist_predict_ms"] = estimates_.lastMs();
    stats_.extras["persist_schedule"] = schedule.name();
    stats_.note = "persistent schedule: " + std::string(schedule.name()) + ": " + schedule.reason;
    return out;
}

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
                renderScheduled(scene, candidate.options);
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

void PersistentPipeline::chooseOrder(const Scene& scene, RenderOptions& nested) {
    // Which order keeps a work-group's patch in cache depends on the scene's layout on screen,
    // which the traced warps do not see: on the H200, 16x8 strips (the megakernel's own
    // work-groups) ran spheres 4-7% faster than 4x16, and cornell, mesh and envmap 4-8% slower.
    std::vector<TrialCandidate> orders;
    for (const char* order : {"4x16", "16x8"}) {
        orders.push_back({order, nested});
        tileOption().set(orders.back().options.pipelineOptions, std::string(order));
    }
    const bool decided = decide(order_, scene, nested, orders);
    tileOption().set(nested.pipelineOptions, order_.chosen);
    stats_.extras["persist_tile"] = order_.chosen;
    stats_.extras["persist_tile_trials_ms"] = order_.trialsMs;
    stats_.extras["persist_tile_decided"] = decided;  // this frame timed the orders
    stats_.note += "; " + order_.chosen + " strips, the faster of two trial frames each";
}

void PersistentPipeline::chooseLoop(const Scene& scene, const RenderOptions& o,
                                    RenderOptions& regrouped) {
    // Both keep a warp's lanes busy where trees disagree; which costs less a step depends on the
    // shading: on the H200 the bounce loop was 2-5% faster than the regrouped loop on four walls
    // of six and 4-7% slower on the two whose noise patterns the regrouped loop sorts.
    RenderOptions bounce = o;
    loopOption().set(bounce.pipelineOptions, std::string("bounce"));
    // Keyed by the options as given: --persistent-batch and --persistent-shadows shape the
    // bounce loop's trial, though the regrouped loop runs without them.
    const bool decided = decide(loop_, scene, o, {{"regrouped", regrouped}, {"bounce", bounce}});
    if (loop_.chosen == "bounce")
        regrouped = bounce;
    else  // the trial's scratch, which can be gigabytes at high bounce limits, is not kept
        for (DeviceBuffer* scratch : {&bounceRays_, &bounceTerms_, &bounceHits_, &bounceOrder_})
            scratch->reset();
    stats_.extras["persist_loop"] = loop_.chosen;
    stats_.extras["persist_loop_trials_ms"] = loop_.trialsMs;
    stats_.extras["persist_loop_decided"] = decided;  // this frame timed the loops
    if (!loop_.refused.empty()) stats_.extras["persist_loop_refused"] = loop_.refused;
    stats_.note += "; the " + loop_.chosen + " loop, the faster of two trial frames each";
}

Image PersistentPipeline::renderFrame(const Scene& scene, const RenderOptions& o) {
    const auto choice = PersistScheduleChoice(scheduleOption().index(o.pipelineOptions));
    if (choice == PersistScheduleChoice::Flags) return renderScheduled(scene, o);
    RenderOptions chosen = chooseSchedule(scene, o);
    if (PersistLoop(loopOption().index(chosen.pipelineOptions)) == PersistLoop::Nested)
        chooseOrder(scene, chosen);
    else
        chooseLoop(scene, o, chosen);
    return renderScheduled(scene, chosen);
}

Image PersistentPipeline::renderScheduled(const Scene& scene, const RenderOptions& o) {
    if (o.adaptiveAa && o.aa > 1)
        throw Error(
            "--adaptive: the persistent megakernel has no adaptive anti-aliasing (use "
            "--pipeline mega)",
            FailureKind::InvalidOption);
    // The weighted megakernel's program: its stack of pending rays is what a work-item keeps.
    RenderOptions weighted = o;
    setMegaLayout(weighted, MegaLayout::Weighted);
    const std::vector<std::string> defines = MegakernelPipeline::defines(scene, weighted);
    const DeviceInfo& dev = cl_.device();
    const auto loop = PersistLoop(loopOption().index(o.pipelineOptions));
    const bool nested = loop == PersistLoop::Nested, lockstep = loop == PersistLoop::Lockstep;
    const bool bounce = loop == PersistLoop::Bounce;
    // The bounce loop's lanes keep no stack of pending rays: its rays wait in global memory.
    stats_.privateBytes = bounce ? 0 : MegakernelPipeline::privateBytes(scene, weighted);
    // The bounce loop's warps meet only between bounces, and a larger group gives each of them
    // more of the batch's rays to take between meetings: it takes 512 lanes on a GPU.
    const long long lanes = laneOption().integer(o.pipelineOptions);
    size_t local = lanes != 0    ? size_t(lanes)
                         : dev.isGpu() ? (bounce ? std::min<size_t>(512, dev.maxWorkGroup) : 128)
                                       : 64;
    const auto regroupBy = PersistRegroup(regroupOption().index(o.pipelineOptions));
    const bool regroup = regroupBy != PersistRegroup::Off;
    checkLanes(dev, local, regroup && !bounce);
    for (const PipelineOption* option : {&batchOption(), &shadowsOption()})
        if (!bounce && !option->isDefault(o.pipelineOptions))
            throw Error(option->flag() + " applies to --persistent-loop bounce only",
                        FailureKind::InvalidOption);
    const bool shadowPass =
        PersistShadows(shadowsOption().index(o.pipelineOptions)) == PersistShadows::Pass;
    if ((nested || lockstep) && regroup)
        throw Error("--persistent-loop " + loopOption().choice(o.pipelineOptions) +
                        " does not go with --persistent-regroup " +
                        regroupOption().choice(o.pipelineOptions) +
                        " (regrouping sorts the flat loop's steps or the bounce loop's bounces)",
                    FailureKind::InvalidOption);
    const long long refill = refillOption().integer(o.pipelineOptions);
    if (refill != 1 && (nested || lockstep || bounce || regroup))
        throw Error(
            "--persistent-refill " + std::to_string(refill) + " applies to the flat loop only (" +
                (nested || bounce ? "--persistent-loop " + loopOption().choice(o.pipelineOptions) +
                                        " takes pixels a work-group at a time"
                 : lockstep ? std::string("--persistent-loop lockstep takes them at once")
                            : "--persistent-regroup takes a pixel a lane at once") +
                ")",
            FailureKind::InvalidOption);
    // The program for work-groups of `local` lanes: its defines, build options and kernel.
    std::vector<std::string> programDefines, buildOptions;
    long long registerCap = 0;
    const auto build = [&](size_t local) {
        // Regrouped: the work-group's local arrays are sized by its work-items.
        programDefines = defines;
        if (regroup && !bounce)
            programDefines.push_back("RT_PERSIST_REGROUP=" + std::to_string(local));
        if (regroup && bounce) programDefines.push_back("RT_PERSIST_BOUNCE_SORT");
        if (shadowPass) programDefines.push_back("RT_PERSIST_BOUNCE_SHADOW_PASS");
        if (regroupBy == PersistRegroup::Material)
            programDefines.push_back("RT_PERSIST_REGROUP_CLASS");
        if (nested) programDefines.push_back("RT_PERSIST_NESTED");
        if (lockstep) programDefines.push_back("RT_PERSIST_LOCKSTEP");
        if (bounce) programDefines.push_back("RT_PERSIST_BOUNCE=" + std::to_string(local));
        // The group size declared to the compiler (persistent.cl, RT_GROUP_LANES), except on
        // NVIDIA.
        if (!dev.nvidia()) programDefines.push_back("RT_REQD_GROUP_SIZE");
        const std::string& tile = tileOption().choice(o.pipelineOptions);
        const size_t by = tile.find('x');
        programDefines.push_back("RT_PERSIST_TILE_W=" + tile.substr(0, by));
        programDefines.push_back("RT_PERSIST_TILE_H=" + tile.substr(by + 1));
        registerCap = persistentRegisterCap(dev, local, registersOption().integer(o.pipelineOptions));
        buildOptions = registerCapBuildOptions(registerCap, dev);
        // On NVIDIA the warp's lanes vote and take pixels together (inline PTX, RT_WARP_PTX).
        const cl::Program program =
            rayLoopProgram("persistent.cl", programDefines, buildOptions, o, {"RT_WARP_PTX"});
        return Kernel(program, bounce    ? "Persistent_RenderBounce"
                               : regroup ? "Persistent_RenderRegrouped"
                                         : "Persistent_Render");
    };
    Kernel kernel = build(local);
    // A build can still be too large for the group (its registers or private memory, or a
    // compiler that assumed smaller groups). Where no --persistent-lanes was asked, the group
    // shrinks to the largest power of two the build takes and the program is built again for it
    // (NVIDIA's driver ran the bounce loop at 121 registers in groups of at most 256, below its
    // 512-lane default); an asked group is refused here by name, not by the launch.
    for (size_t fits = kernel.maxGroup(dev.device); fits < local;
         fits = kernel.maxGroup(dev.device)) {
        if (lanes == 0 && fits >= 16) {
            size_t smaller = 16;
            while (smaller * 2 <= fits) smaller *= 2;
            local = smaller;
            kernel = build(local);
            continue;
        }
        // The registers the build log gives (NVIDIA), which decide the group on most GPUs.
        const auto used = stats_.kernelResources.find(kernel.name() + ".registers");
        const std::string registers =
            used == stats_.kernelResources.end()
                ? ""
                : " (" + std::to_string(std::lround(used->second)) + " registers a work-item" +
                      (registerCap ? ", capped at " + std::to_string(registerCap) : "") + ")";
        throw Error("--persistent-lanes " + std::to_string(local) + ": " + kernel.name() +
                        " as built for " + dev.name + registers + " runs at most " +
                        std::to_string(fits) + " work-items a work-group; lower --persistent-lanes",
                    FailureKind::InvalidOption);
    }
    stats_.extras["persist_lanes"] = local;
    DeviceScene& deviceScene = this->deviceScene(scene, o.accel);
    const size_t bytes = size_t(o.width) * o.height * 3 * sizeof(float);
    try {
        image_.ensure(cl_, bytes, "the image buffer");
        next_.ensure(cl_, sizeof(cl_int), "the persistent megakernel's pixel counter");
    } catch (const cl::Error& e) {
        throwClError(e, "preparing persistent-megakernel buffers");
    }
    stats_.addBuffer("image", bytes);
    const size_t most = workItems(dev, o, local);
    if (registerCap != 0) stats_.extras["persist_register_cap"] = registerCap;
    kernel.set("image", image_.get()).set("next", next_.get());
    if (bounce)
        setBounceScratch(kernel, scene, o, most / local, regroup || shadowPass);
    else
        kernel.set("refill", cl_int(refill));
    dev::RenderSettings settings = makeSettings(scene, o);
    deviceScene.setArgs(kernel, settings);
    std::string key = std::to_string(o.width) + "x" + std::to_string(o.height);
    for (const std::string& d : programDefines) key += " " + d;
    for (const std::string& b : buildOptions) key += " " + b;
    key += " b" + std::to_string(o.bounces) + " g" + std::to_string(most);
    const int first = o.rowBegin, last = o.lastRow();
    if (first != 0 || last != o.height)
        key += " rows " + std::to_string(first) + "-" + std::to_string(last);
    planner_.begin(o.maxLaunchMs, key, o.width, 1);
    Image out(o.width, o.height);
    try {
        startRayCount(o);
        // Tiles of whole rows, or of part of one row, when --max-launch-ms asks for them.
        for (int row0 = first; row0 < last;) {
            const LaunchTile tile = planner_.next(last - row0);
            const int start = row0 * o.width + (tile.partialRow() ? tile.col0 : 0);
            const int count = tile.partialRow() ? tile.cols : tile.rows * o.width;
            cl_.queue().enqueueFillBuffer(next_.get(), cl_int(0), 0, sizeof(cl_int));
            kernel.set("first", cl_int(start)).set("count", cl_int(count));
            const size_t global = std::min(most, (size_t(count) + local - 1) / local * local);
            cl::Event e;
            cl_.queue().enqueueNDRangeKernel(kernel.get(), cl::NullRange, cl::NDRange(global),
                                             cl::NDRange(local), nullptr, &e);
            e.wait();
            const double ms = eventMs(e);
            planner_.record(tile, ms);
            stats_.addKernel("persistent", ms);
            ++stats_.launches;
            if (tile.partialRow() && tile.col0 + tile.cols < o.width) continue;  // row goes on
            row0 += tile.rows;
            reportProgress(row0 - first, last - first);
        }
        const size_t rowBytes = size_t(o.width) * 3 * sizeof(float);
        cl_.queue().enqueueReadBuffer(image_.get(), CL_TRUE, size_t(first) * rowBytes,
                                      size_t(last - first) * rowBytes,
                                      out.rgb.data() + size_t(first) * o.width * 3);
        finishRayCount(o);
    } catch (const cl::Error& e) {
        throwClError(e, "persistent-megakernel frame on " + dev.name,
                     bounce ? std::string("the bounce loop keeps its rays in scratch buffers; "
                                          "lower --persistent-batch or --persistent-groups")
                            : "each work-item keeps " + std::to_string(stats_.privateBytes) +
                                  " bytes of pending rays; lower --bounces or --persistent-groups");
    }
    stats_.extras["work_items"] = most;
    return out;
}

void PersistentPipeline::setBounceScratch(Kernel& kernel, const Scene& scene,
                                          const RenderOptions& o, size_t groups, bool staged) {
    // Per work-group, as persistent.cl's Persistent_RenderBounce indexes it: two lists as long as
    // the widest bounce a batch can reach (every ray of the last one glass), a tree of terms a
    // pixel, and, staged (sorted or with a shadow pass), a hit and an index for each ray of one
    // such list.
    const long long batch = batchOption().integer(o.pipelineOptions);
    const int branching = scene.branching();
    const size_t widest = size_t(batch) << (o.bounces * (branching - 1));
    const size_t rayBytes = groups * 2 * widest * sizeof(dev::BounceRay);
    const size_t termBytes = groups * size_t(batch) * size_t(treeNodeCount(branching, o.bounces)) *
                             sizeof(dev::BounceTerm);
    const size_t hitBytes = staged ? groups * widest * sizeof(dev::BounceHit) : 0;
    const size_t orderBytes = staged ? groups * widest * sizeof(cl_int) : 0;
    const size_t total = rayBytes + termBytes + hitBytes + orderBytes;
    const DeviceInfo& dev = cl_.device();
    const auto mib = [](size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; };
    // The kernel indexes a list with an int.
    if (std::max({rayBytes, termBytes, hitBytes}) > dev.maxAlloc || total > dev.globalMem / 2 ||
        widest > size_t(std::numeric_limits<cl_int>::max()))
        throw Error("--persistent-batch " + std::to_string(batch) + ": " + std::to_string(groups) +
                        " work-groups tracing batches bounce by " + "bounce at --bounces " +
                        std::to_string(o.bounces) + " need " + mib(rayBytes) + " of rays, " +
                        mib(termBytes) + " of terms" +
                        (staged ? " and " + mib(hitBytes + orderBytes) + " of staged hits"
                                : std::string()) +
                        ", and " + dev.name + " allocates at most " + mib(dev.maxAlloc) +
                        " a buffer and half its " + mib(dev.globalMem) +
                        " in all here; lower --persistent-batch, --persistent-groups or "
                        "--bounces",
                    FailureKind::InvalidOption);
    try {
        bounceRays_.ensure(cl_, rayBytes, "the bounce loop's ray lists");
        bounceTerms_.ensure(cl_, termBytes, "the bounce loop's trees of terms");
        if (staged) {
            bounceHits_.ensure(cl_, hitBytes, "the bounce loop's staged hits");
            bounceOrder_.ensure(cl_, orderBytes, "the bounce loop's hit indices");
        }
    } catch (const cl::Error& e) {
        throwClError(e, "preparing the persistent megakernel's bounce scratch");
    }
    stats_.addBuffer("bounce rays", rayBytes);
    stats_.addBuffer("bounce terms", termBytes);
    kernel.set("rays", bounceRays_.get()).set("terms", bounceTerms_.get());
    kernel.set("batch", cl_int(batch)).set("widest", cl_int(widest));
    if (staged) {
        stats_.addBuffer("bounce hits", hitBytes);
        stats_.addBuffer("bounce order", orderBytes);
        kernel.set("hits", bounceHits_.get()).set("order", bounceOrder_.get());
    }
}

void registerPersistentMegakernel(PipelineRegistry& registry) {
    PipelineInfo p;
    p.name = "persist";
    p.title = "persistent megakernel";
    p.family = "megakernel";
    p.description =
        "the weighted megakernel with persistent threads: a device-filling launch whose "
        "work-items take pixels from a global counter as their ray trees end "
        "(--persistent-groups N, --persistent-refill N, --persistent-regroup pattern|material, "
        "--persistent-lanes N, --persistent-max-registers N, --persistent-loop "
        "nested|lockstep|bounce, --persistent-batch N, --persistent-shadows inline|pass, "
        "--persistent-tile WxH, or --persistent-schedule auto to let warps traced on the CPU "
        "choose)";
    p.supports = {.adaptiveAa = false, .tiling = false, .rowWindow = true};
    p.options = {groupsOption(), refillOption(), regroupOption(), laneOption(), registersOption(),
                 loopOption(),   batchOption(),  shadowsOption(), tileOption(), scheduleOption()};
    // Tests and the smoke check run the default schedule, the regrouped one, whose hits move
    // between lanes through local memory, the nested loop, the lockstep loop (whose warp votes
    // only NVIDIA runs), the bounce loop (whose rays move between lanes through global memory),
    // as it is and staged (each bounce's hits sorted by material, their shadow rays cast in a
    // pass of their own), and the schedule auto chooses (256 regrouped lanes a group where
    // it regroups).
    PipelineVariant regrouped{"regrouped", {}}, nested{"nested", {}}, lockstep{"lockstep", {}},
        bounce{"bounce", {}}, bounceStaged{"bounce-staged", {}}, automatic{"auto", {}};
    regroupOption().set(regrouped.values, std::string("material"));
    loopOption().set(nested.values, std::string("nested"));
    loopOption().set(lockstep.values, std::string("lockstep"));
    loopOption().set(bounce.values, std::string("bounce"));
    loopOption().set(bounceStaged.values, std::string("bounce"));
    regroupOption().set(bounceStaged.values, std::string("material"));
    shadowsOption().set(bounceStaged.values, std::string("pass"));
    scheduleOption().set(automatic.values, std::string("auto"));
    p.variants = {
        PipelineVariant{"", {}}, regrouped, nested, lockstep, bounce, bounceStaged, automatic};
    p.make = [](ClContext* cl) { return std::make_unique<PersistentPipeline>(*cl); };
    registry.add(std::move(p));
}

}  // namespace rt
