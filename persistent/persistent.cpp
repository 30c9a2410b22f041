// rtlab — the persistent megakernel's host driver (persistent.h): its options, and one frame in
// one of its schedules (schedules.h).
#include "persistent/persistent.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/pipeline_registry.h"
#include "megakernel/megakernel.h"
#include "megakernel/megakernel_options.h"
#include "persistent/phases.h"

namespace rt {

namespace {

const PipelineOption& scheduleOption() {
    static const PipelineOption o{
        .name = "persistent-schedule",
        .type = PipelineOption::Type::Choice,
        .help =
            [] {
                std::string help = "Persistent megakernel: ";
                for (const PersistSchedule& s : persistSchedules())
                    help += std::string(s.help) + ", ";
                char rule[96];
                std::snprintf(rule, sizeof rule,
                              "below %.1f busy lanes of 32 or from %.1f objects a warp",
                              kRegroupBelowLanes, kRegroupFromObjects);
                return help +
                       "or auto (warps traced on the CPU, as `rtlab predict` does, choose: " +
                       rule +
                       ", two regrouped work-groups of 256 lanes a compute unit at most 128 "
                       "registers, or the bounce loop, whichever two trial frames each find "
                       "faster; otherwise the nested loop, in 4x16 or 16x8 strips, the same "
                       "way) [flat]";
            }(),
        .defaultValue = "flat",
        .choices =
            [] {
                std::vector<std::string> names;
                for (const PersistSchedule& s : persistSchedules()) names.push_back(s.name);
                names.push_back("auto");
                return names;
            }(),
        .sweepKey = "persistent-schedule",
        .cellTag = "H",
        .label = "{} schedule",
    };
    return o;
}

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

// Work-items per work-group; 0 takes the schedule's default (PersistSchedule::defaultLanes).
const PipelineOption& laneOption() {
    static const PipelineOption o{
        .name = "persistent-lanes",
        .type = PipelineOption::Type::Integer,
        .help =
            "Persistent megakernel: work-items per work-group, 16..1024, at most what the "
            "kernel as built runs (and, regrouped, what local memory holds): the lanes that the "
            "regrouped loop sorts hits among, that the nested loop hands pixels to together, or "
            "that the bounce loop traces a batch of twice as many pixels with [128 on a GPU, 512 "
            "in the bounce loop; 64 elsewhere; lowered to the largest power of two the kernel "
            "runs where not given]",
        .defaultValue = 0ll,
        .min = 16,
        .max = 1024,
        .sweepKey = "persistent-lanes",
        .cellTag = "N",
        .label = "{} lanes a group",
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

// The largest power of two of at least 16 that is at most `fits`; 0 where none is.
size_t lanesThatFit(size_t fits) {
    if (fits < 16) return 0;
    size_t lanes = 16;
    while (lanes * 2 <= fits) lanes *= 2;
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

std::vector<std::string> PersistentPipeline::phaseNames() const { return RT_PHASE_NAMES; }

void setPersistentScheduleAuto(RenderOptions& o) {
    scheduleOption().set(o.pipelineOptions, std::string("auto"));
}

Image PersistentPipeline::renderFrame(const Scene& scene, const RenderOptions& o) {
    if (o.adaptiveAa && o.aa > 1)
        throw Error(
            "--adaptive: the persistent megakernel has no adaptive anti-aliasing (use "
            "--pipeline mega)",
            FailureKind::InvalidOption);
    const std::string& name = scheduleOption().choice(o.pipelineOptions);
    if (name == "auto") return renderRun(scene, o, chooseSchedule(scene, o));
    Run run;
    run.schedule = &persistSchedule(name);
    run.lanes = laneOption().integer(o.pipelineOptions);
    run.groups = groupsOption().integer(o.pipelineOptions);
    run.registers = registersOption().integer(o.pipelineOptions);
    return renderRun(scene, o, run);
}

Image PersistentPipeline::renderRun(const Scene& scene, const RenderOptions& o, const Run& run) {
    const PersistSchedule& schedule = *run.schedule;
    const bool bounce = schedule.loop == PersistSchedule::Loop::Bounce;
    // The weighted megakernel's program: its stack of pending rays is what a work-item keeps.
    RenderOptions weighted = o;
    setMegaLayout(weighted, MegaLayout::Weighted);
    const std::vector<std::string> defines = MegakernelPipeline::defines(scene, weighted);
    const DeviceInfo& dev = cl_.device();
    // The bounce loop's lanes keep no stack of pending rays: its rays wait in global memory.
    stats_.privateBytes =
        schedule.keepsStack() ? MegakernelPipeline::privateBytes(scene, weighted) : 0;
    size_t local = run.lanes != 0 ? size_t(run.lanes) : schedule.defaultLanes(dev);
    checkLanes(dev, local, schedule.loop == PersistSchedule::Loop::Regrouped);

    // The program for work-groups of `local` lanes.
    std::vector<std::string> programDefines, buildOptions;
    long long registerCap = 0;
    const auto build = [&] {
        programDefines = defines;
        for (std::string& d : schedule.defines(local, dev)) programDefines.push_back(std::move(d));
        registerCap = persistentRegisterCap(dev, local, run.registers);
        buildOptions = registerCapBuildOptions(registerCap, dev);
        // On NVIDIA the warp's lanes vote and take pixels together (inline PTX, RT_WARP_PTX).
        return Kernel(
            rayLoopProgram(schedule.file(), programDefines, buildOptions, o, {"RT_WARP_PTX"}),
            schedule.kernel());
    };
    Kernel kernel = build();
    // A build can still be too large for the group (its registers or private memory, or a
    // compiler that assumed smaller groups). Where --persistent-lanes was not given, the group
    // shrinks to the largest power of two the build runs and the program is built again for it
    // (NVIDIA's driver ran the bounce loop at 121 registers in groups of at most 256, below its
    // 512-lane default); a given group is refused here by name, not by the launch.
    for (size_t fits = kernel.maxGroup(dev.device); fits < local;
         fits = kernel.maxGroup(dev.device)) {
        if (run.lanes == 0 && lanesThatFit(fits) != 0) {
            local = lanesThatFit(fits);
            kernel = build();
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
    if (registerCap != 0) stats_.extras["persist_register_cap"] = registerCap;
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
    // Work-items of one launch: --persistent-groups work-groups a compute unit.
    const size_t most = std::max<cl_uint>(dev.computeUnits, 1) * size_t(run.groups) * local;
    kernel.set("image", image_.get()).set("next", next_.get());
    if (bounce) bounce_.bind(cl_, kernel, stats_, scene, o, most / local, local, schedule.staged);
    dev::RenderSettings settings = makeSettings(scene, o);
    deviceScene.setArgs(kernel, settings);
    const int first = o.rowBegin, last = o.lastRow();
    planner_.begin(o.maxLaunchMs,
                   launchKey(o, programDefines, buildOptions, " g" + std::to_string(most)), o.width,
                   1);
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
                                          "lower --persistent-lanes or --persistent-groups")
                            : "each work-item keeps " + std::to_string(stats_.privateBytes) +
                                  " bytes of pending rays; lower --bounces or --persistent-groups");
    }
    stats_.extras["work_items"] = most;
    return out;
}

// --persistent-schedule auto's option checks and trials (persistent_auto.cpp) need these.
const PipelineOption& persistScheduleOption() { return scheduleOption(); }
std::vector<const PipelineOption*> persistSettingOptions() {
    return {&laneOption(), &groupsOption(), &registersOption()};
}

void registerPersistentMegakernel(PipelineRegistry& registry) {
    PipelineInfo p;
    p.name = "persist";
    p.title = "persistent megakernel";
    p.family = "megakernel";
    p.description =
        "the weighted megakernel with persistent threads: a device-filling launch whose "
        "work-items take pixels from a global counter as their ray trees end "
        "(--persistent-schedule flat|nested|nested-16x8|regrouped|bounce|bounce-staged, or auto "
        "to let warps traced on the CPU choose; --persistent-lanes N, --persistent-groups N, "
        "--persistent-max-registers N)";
    p.supports = {.adaptiveAa = false, .tiling = false, .rowWindow = true};
    p.options = {scheduleOption(), laneOption(), groupsOption(), registersOption()};
    // Tests and the smoke check run every schedule at its defaults, and the one auto chooses.
    p.variants = {PipelineVariant{"", {}}};
    for (const PersistSchedule& s : persistSchedules()) {
        if (s.name == std::string("flat") || s.name == std::string("nested-16x8")) continue;
        PipelineVariant v{s.name, {}};
        scheduleOption().set(v.values, std::string(s.name));
        p.variants.push_back(v);
    }
    PipelineVariant automatic{"auto", {}};
    scheduleOption().set(automatic.values, std::string("auto"));
    p.variants.push_back(automatic);
    p.make = [](ClContext* cl) { return std::make_unique<PersistentPipeline>(*cl); };
    registry.add(std::move(p));
}

}  // namespace rt
