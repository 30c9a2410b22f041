// Persistent megakernel: the weighted megakernel's image to the bit on every standard scene,
// whoever renders which pixel (one work-group per compute unit or many, one launch or pieces
// under --max-launch-ms, a row window, frames whose sides are no multiple of the strips it
// hands pixels out in, a loop over pixels around the loop over rays, work-groups that regroup
// hits, a wavefront inside the launch), the same rays counted, and one clear error per option it
// refuses.
#include "persistent/persistent.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdlib>
#include <tuple>

#include "core/error.h"
#include "core/kernel.h"
#include "megakernel/megakernel.h"
#include "megakernel/megakernel_options.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"
#include "wavefront/bounce/bounce_state.h"

namespace rt {
namespace {

using test::load;
using test::sameBits;

RenderOptions weighted(const Scene& scene, int bounces, int aa) {
    RenderOptions o = scene.defaults;
    o.width = 40;
    o.height = 30;
    o.bounces = bounces;
    o.aa = aa;
    setMegaLayout(o, MegaLayout::Weighted);
    return o;
}

// Sets the persistent megakernel's option `name` (a flag name without its dashes).
template <typename Value>
void setOption(RenderOptions& o, const std::string& name, Value value) {
    for (const PipelineOption& option : pipelineInfo("persist").options)
        if (option.name == name) return option.set(o.pipelineOptions, value);
    FAIL() << "persist has no option " << name;
}

void setGroups(RenderOptions& o, long long groups) { setOption(o, "persistent-groups", groups); }
void setSchedule(RenderOptions& o, const std::string& schedule) {
    setOption(o, "persistent-schedule", schedule);
}

class PersistentVsMega : public ::testing::TestWithParam<const char*> {};

TEST_P(PersistentVsMega, SameBitsAsTheWeightedMegakernel) {
    Scene scene = load(GetParam());
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    for (int b : {0, 3, 8}) {
        RenderOptions o = weighted(scene, b, b == 3 ? 2 : 1);
        const Image m = mega.render(scene, o);
        EXPECT_TRUE(sameBits(m, persist.render(scene, o))) << GetParam() << " B=" << b;
        setGroups(o, 1);  // fewer work-items than pixels: each takes many in turn
        EXPECT_TRUE(sameBits(m, persist.render(scene, o)))
            << GetParam() << " B=" << b << " 1 group";
    }
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, PersistentVsMega, ::testing::ValuesIn(test::kScenes));

TEST(Persistent, PiecesAndRowWindowsKeepTheBits) {
    Scene scene = load("cornell");
    RenderOptions o = weighted(scene, 4, 1);
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    const Image m = mega.render(scene, o);
    // The nested loop's work-group takes a pixel a lane: a piece of one row leaves lanes without.
    for (const char* loop : {"flat", "nested", "regrouped", "bounce", "bounce-staged"}) {
        setSchedule(o, loop);
        RenderOptions capped = o;
        capped.maxLaunchMs = 1e-6;  // every launch over the cap: a row, or part of one, at a time
        const Image pieces = persist.render(scene, capped);
        EXPECT_GT(persist.stats().launches, o.height) << loop;
        EXPECT_TRUE(sameBits(m, pieces)) << loop;
        RenderOptions window = o;
        window.rowBegin = 7;
        window.rowEnd = 19;
        const Image part = persist.render(scene, window);
        for (int y = 7; y < 19; ++y)
            for (int i = 0; i < o.width * 3; ++i)
                ASSERT_EQ(part.rgb[size_t(y * o.width * 3 + i)], m.rgb[size_t(y * o.width * 3 + i)])
                    << loop << ", row " << y;
    }
}

TEST(Persistent, CutTilesKeepTheBits) {
    Scene scene = load("cornell");
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    RenderOptions o = weighted(scene, 3, 2);
    o.width = 37;   // strips of 4 columns and one of 1, of 16 and one of 5
    o.height = 23;  // one band of 16 rows and one of 7, bands of 8 and one of 7
    const Image m = mega.render(scene, o);
    for (const char* schedule : {"flat", "nested", "nested-16x8"}) {
        setSchedule(o, schedule);
        EXPECT_TRUE(sameBits(m, persist.render(scene, o))) << schedule;
        setGroups(o, 1);
        EXPECT_TRUE(sameBits(m, persist.render(scene, o))) << schedule << ", 1 group";
        setGroups(o, 4);
    }
}

// Regrouped, a lane shades other lanes' hits: the divergence scene mixes procedural patterns,
// mirrors and glass, so most steps move hits between lanes. Each pixel's terms still arrive in
// its own order, so the bits and the counted rays stay the weighted megakernel's, whatever the
// key and however many lanes sort together.
TEST(Persistent, RegroupedKeepsTheBitsAndTheRays) {
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    for (const char* name : {"divergence", "spheres", "envmap"}) {
        Scene scene = load(name);
        RenderOptions o = weighted(scene, 4, 2);
        o.width = 37;
        o.height = 23;
        o.countRays = true;
        const Image m = mega.render(scene, o);
        for (const char* key : {"pattern"}) {
            RenderOptions r = o;
            setSchedule(r, "regrouped");
            EXPECT_TRUE(sameBits(m, persist.render(scene, r))) << name << " " << key;
            ASSERT_TRUE(persist.stats().raysCounted);
            EXPECT_EQ(persist.stats().rays, mega.stats().rays) << name << " " << key;
            setGroups(r,
                      1);  // one work-group a compute unit: many pixels a lane, groups leave late
            EXPECT_TRUE(sameBits(m, persist.render(scene, r))) << name << " " << key << " 1 group";
            setOption(r, "persistent-lanes", 32ll);  // more groups, fewer lanes to sort among
            EXPECT_TRUE(sameBits(m, persist.render(scene, r))) << name << " " << key << " 32";
        }
    }
}

// The bounce loop traces a work-group's batch of pixels (twice its lanes) bounce by bounce, each
// bounce's rays compacted in global memory, so a lane traces other pixels' rays and a pixel's
// terms are summed after its whole tree is traced. The divergence scene branches at glass and
// mirrors on most pixels; the frame's last batch is cut (851 pixels in batches of 128, 64 and
// 96), and B = 8 at AA 2 widens the lists to 256 rays a pixel. Staged, each bounce's hits are
// shaded in pattern order, not the trace's, and their shadow rays are cast by other lanes than the
// ones that traced them.
TEST(Persistent, BounceLoopKeepsTheBitsAndTheRays) {
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    for (const char* name : {"divergence", "spheres", "envmap"}) {
        Scene scene = load(name);
        for (int b : {0, 4, 8}) {
            RenderOptions o = weighted(scene, b, b == 0 ? 1 : 2);
            o.width = 37;
            o.height = 23;
            o.countRays = true;
            const Image m = mega.render(scene, o);
            for (const char* schedule : {"bounce", "bounce-staged"}) {
                RenderOptions r = o;
                setSchedule(r, schedule);
                // Scratch grows with C^B a pixel: at B = 8, one group a compute unit and 64 lanes
                // (batches of 128) keep it near 8 MB a unit, which any device holds.
                if (b == 8) {
                    setGroups(r, 1);
                    setOption(r, "persistent-lanes", 64ll);
                }
                EXPECT_TRUE(sameBits(m, persist.render(scene, r)))
                    << name << " B=" << b << " " << schedule;
                ASSERT_TRUE(persist.stats().raysCounted);
                EXPECT_EQ(persist.stats().rays, mega.stats().rays)
                    << name << " B=" << b << " " << schedule;
                // Groups of one warp, and of a warp and a half (groups need not be a power of
                // two).
                for (long long lanes : {32ll, 48ll}) {
                    setOption(r, "persistent-lanes", lanes);
                    EXPECT_TRUE(sameBits(m, persist.render(scene, r)))
                        << name << " B=" << b << ", " << schedule << ", " << lanes << " lanes";
                    EXPECT_EQ(persist.stats().rays, mega.stats().rays)
                        << name << " B=" << b << ", " << schedule << ", " << lanes << " lanes";
                }
            }
        }
    }
}

// The bounce loop's records have the host's layout on the device (bounce_state.h).
TEST(Persistent, BounceStateHasTheHostsLayout) {
    ClContext& cl = test::device();
    Kernel kernel(cl.program("bounce_probe.cl", {}), "Bounce_Sizes");
    cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, 4 * sizeof(cl_uint));
    kernel.set("out", out);
    cl.queue().enqueueNDRangeKernel(kernel.get(), cl::NullRange, cl::NDRange(1));
    cl_uint got[4] = {};
    cl.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof got, got);
    EXPECT_EQ(got[0], sizeof(dev::BounceRay));
    EXPECT_EQ(got[1], sizeof(dev::BounceTerm));
    EXPECT_EQ(got[2], sizeof(dev::BounceHit));
    EXPECT_EQ(got[3], offsetof(dev::BounceHit, ray));
}

// The bounce loop's scratch holds the widest bounce a batch can reach: at B = 16 on a scene
// with glass, 2^16 rays a pixel; batches of 2048 pixels (1024 lanes) make that 12.9 GB of ray
// lists a work-group. Expected refused wherever it is past the device's largest buffer.
TEST(Persistent, BounceLoopRefusesScratchPastTheDevice) {
    Scene scene = load("divergence");
    ASSERT_EQ(scene.branching(), 2);
    RenderOptions o = weighted(scene, 16, 1);
    setSchedule(o, "bounce");
    setOption(o, "persistent-lanes", 1024ll);
    const DeviceInfo& dev = test::device().device();
    if (dev.maxWorkGroup < 1024) GTEST_SKIP() << dev.name << " runs fewer than 1024 lanes a group";
    const double rayBytes = 2.0 * 2048 * 65536 * sizeof(dev::BounceRay);  // one work-group's
    if (rayBytes <= double(dev.maxAlloc))
        GTEST_SKIP() << dev.name << " allocates " << dev.maxAlloc << " bytes a buffer";
    PersistentPipeline persist(test::device());
    try {
        persist.render(scene, o);
        FAIL() << "scratch past the device was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("the bounce loop: ", 0), 0u) << what;
        EXPECT_NE(what.find("batches of 2048 pixels"), std::string::npos) << what;
        EXPECT_NE(what.find("--bounces 16"), std::string::npos) << what;
        EXPECT_NE(what.find("MiB of rays"), std::string::npos) << what;
    }
}

// A work-group size the device cannot run is refused by name before anything is built: past
// its work-group limit, or, regrouped, past its local memory (160 bytes a lane).
TEST(Persistent, RefusesMoreLanesThanTheDeviceRuns) {
    Scene scene = load("spheres");
    const DeviceInfo& dev = test::device().device();
    PersistentPipeline persist(test::device());
    for (bool regroup : {false, true}) {
        RenderOptions o = weighted(scene, 1, 1);
        o.width = 8;
        o.height = 4;
        if (regroup) setSchedule(o, "regrouped");
        const long long lanes = 1024;
        setOption(o, "persistent-lanes", lanes);
        const bool fits =
            size_t(lanes) <= dev.maxWorkGroup && (!regroup || size_t(lanes) * 160 <= dev.localMem);
        try {
            persist.render(scene, o);
            EXPECT_TRUE(fits) << "no error for 1024 lanes, regroup " << regroup;
        } catch (const Error& e) {
            const std::string what = e.what();
            // Within the device's limits the kernel as built may still take fewer lanes.
            EXPECT_TRUE(!fits || what.find(" as built for ") != std::string::npos) << what;
            EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
            EXPECT_EQ(what.rfind("--persistent-lanes 1024: ", 0), 0u) << what;
        }
    }
}

// A kernel as built may run fewer work-items a group than the device's limit (NVIDIA's driver
// ran the bounce loop at 121 registers in groups of at most 256, below its 512-lane default).
// No default may be one the driver refuses: every variant at its defaults still renders the
// weighted megakernel's bits in the largest power of two the kernel takes, and a group that was
// asked is refused by name. RTLAB_KERNEL_GROUP_LIMIT stands in for such a build.
TEST(Persistent, DefaultLanesFitWhatTheKernelRuns) {
    Scene scene = load("cornell");
    RenderOptions base = weighted(scene, 3, 1);
    MegakernelPipeline mega(test::device());
    const Image m = mega.render(scene, base);
    ASSERT_EQ(setenv("RTLAB_KERNEL_GROUP_LIMIT", "24", 1), 0);
    for (const PipelineVariant& variant : pipelineInfo("persist").variants) {
        PersistentPipeline persist(test::device());
        RenderOptions o = base;
        o.pipelineOptions.setAll(variant.values);
        const Image image = persist.render(scene, o);
        EXPECT_TRUE(sameBits(m, image)) << "variant " << variant.name;
        const auto lanes = persist.stats().extras.find("persist_lanes");
        ASSERT_NE(lanes, persist.stats().extras.end()) << "variant " << variant.name;
        EXPECT_EQ(lanes->get<long long>(), 16) << "variant " << variant.name;
    }
    RenderOptions asked = base;
    setOption(asked, "persistent-lanes", 32ll);
    PersistentPipeline persist(test::device());
    try {
        persist.render(scene, asked);
        ADD_FAILURE() << "32 asked lanes ran where the kernel takes 24";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        EXPECT_NE(std::string(e.what()).find("runs at most 24 work-items"), std::string::npos)
            << e.what();
    }
    unsetenv("RTLAB_KERNEL_GROUP_LIMIT");
}

// A work-group's lanes share the registers of one multiprocessor: 65,536 on NVIDIA's recent
// GPUs, given to a warp in units of 8 a lane, at most 255 a lane.
TEST(Persistent, CapsRegistersSoThatAGroupFits) {
    DeviceInfo gpu;
    gpu.name = "a GPU";
    gpu.registersPerGroup = 65536;
    EXPECT_EQ(persistentRegisterCap(gpu, 128, 0), 0);  // 512 a lane: any build fits
    EXPECT_EQ(persistentRegisterCap(gpu, 256, 0), 0);
    EXPECT_EQ(persistentRegisterCap(gpu, 512, 0), 128);
    EXPECT_EQ(persistentRegisterCap(gpu, 1024, 0), 64);
    EXPECT_EQ(persistentRegisterCap(gpu, 384, 0), 168);  // 170 a lane, in units of 8
    EXPECT_EQ(persistentRegisterCap(gpu, 500, 0), 128);  // a group's last warp is whole
    EXPECT_EQ(persistentRegisterCap(gpu, 512, 96), 96);  // an asked cap that fits is kept
    EXPECT_EQ(persistentRegisterCap(gpu, 1024, 64), 64);
    try {
        persistentRegisterCap(gpu, 1024, 80);
        FAIL() << "80 registers for 1024 lanes were accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        EXPECT_EQ(std::string(e.what()),
                  "--persistent-max-registers 80: 1024 work-items a work-group "
                  "(--persistent-lanes) share a GPU's 65536 registers, at most 64 each; lower "
                  "either flag");
    }
    DeviceInfo silent;  // says nothing of its registers: the asked cap, or none
    EXPECT_EQ(persistentRegisterCap(silent, 1024, 0), 0);
    EXPECT_EQ(persistentRegisterCap(silent, 1024, 80), 80);
}

TEST(Persistent, CountsTheRaysTheMegakernelCounts) {
    Scene scene = load("spheres");
    RenderOptions o = weighted(scene, 5, 2);
    o.countRays = true;
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    mega.render(scene, o);
    persist.render(scene, o);
    ASSERT_TRUE(persist.stats().raysCounted);
    EXPECT_EQ(persist.stats().rays, mega.stats().rays);
    EXPECT_GT(persist.stats().rays[RT_RAY_PRIMARY], 0u);
}

TEST(Persistent, AutoScheduleRegroupsWhereLanesOrPatternsDisagree) {
    LaneEstimate e;
    e.objectsPerWarp = 1.0;
    e.busyLanes = kRegroupBelowLanes - 0.01;
    EXPECT_TRUE(choosePersistentSchedule(e).regroup);
    e.busyLanes = kRegroupBelowLanes;
    EXPECT_FALSE(choosePersistentSchedule(e).regroup);
    EXPECT_EQ(choosePersistentSchedule(e).reason.rfind(
                  "27.8 busy lanes of 32 predicted and 1.0 objects a warp", 0),
              0u)
        << choosePersistentSchedule(e).reason;
    e.objectsPerWarp = kRegroupFromObjects;  // busy lanes, but several patterns a warp
    EXPECT_TRUE(choosePersistentSchedule(e).regroup);
    EXPECT_EQ(choosePersistentSchedule(e).reason.rfind("1.6 objects a warp (at least 1.6)", 0), 0u)
        << choosePersistentSchedule(e).reason;
}

// --persistent-schedule auto on a frame whose warps all miss (32 busy lanes: the nested loop) and
// on one of mirrors and glass at 40x30 (fewer: regrouped), each the weighted megakernel's bits.
TEST(Persistent, AutoScheduleKeepsTheBitsOnBothSides) {
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    for (const auto& [name, width, height] :
         {std::tuple{"empty", 64, 32}, std::tuple{"spheres", 40, 30}}) {
        Scene scene = load(name);
        RenderOptions o = weighted(scene, 4, 1);
        o.width = width;
        o.height = height;
        o.countRays = true;
        const bool regroup = choosePersistentSchedule(estimateBusyLanes(scene, o)).regroup;
        EXPECT_EQ(regroup, std::string(name) == "spheres") << name;
        setOption(o, "persistent-schedule", std::string("auto"));
        EXPECT_TRUE(sameBits(mega.render(scene, o), persist.render(scene, o))) << name;
        EXPECT_EQ(persist.stats().extras.value("persist_schedule", ""),
                  regroup ? "regrouped" : "nested")
            << name;
        ASSERT_TRUE(persist.stats().raysCounted) << name;
        EXPECT_EQ(persist.stats().rays, mega.stats().rays) << name;
    }
}

// An estimate handed in (as `--pipeline auto` hands its own) decides the schedule while the scene
// and settings stay the same: here one that says the spheres' warps agree, so the nested loop,
// where the scene's own warps would regroup. Other settings trace the scene again.
TEST(Persistent, AutoScheduleUsesAnEstimateHandedIn) {
    Scene scene = load("spheres");
    PersistentPipeline persist(test::device());
    RenderOptions o = weighted(scene, 4, 1);
    setPersistentScheduleAuto(o);
    ASSERT_TRUE(choosePersistentSchedule(estimateBusyLanes(scene, o)).regroup);
    LaneEstimate agree;
    agree.lanes = 32;
    agree.busyLanes = 32;
    agree.objectsPerWarp = 1;
    persist.useLaneEstimate(scene, o, agree, 123.0);
    persist.render(scene, o);
    EXPECT_EQ(persist.stats().extras.value("persist_schedule", ""), "nested");
    EXPECT_EQ(persist.stats().extras.value("persist_predict_ms", 0.0), 123.0);
    EXPECT_EQ(persist.stats().extras.value("persist_busy_lanes", 0.0), 32.0);
    o.bounces = 3;
    persist.render(scene, o);
    EXPECT_EQ(persist.stats().extras.value("persist_schedule", ""), "regrouped");
    EXPECT_NE(persist.stats().extras.value("persist_predict_ms", 0.0), 123.0);
}

// A choice auto made by trial frames, as a frame's extras give it: the candidates' times under
// `<what>_trials_ms` (`count` of them), the choice under `<what>`, which is the fastest, and
// `<what>_decided` (this frame timed them). Returns the choice.
std::string trialChoice(const nlohmann::json& x, const std::string& what, size_t count) {
    const nlohmann::json& trials = x.at(what + "_trials_ms");
    EXPECT_EQ(trials.size(), count) << trials.dump();
    const std::string chosen = x.value(what, "");
    EXPECT_TRUE(trials.contains(chosen)) << x.dump();
    if (!trials.contains(chosen)) return chosen;
    for (const auto& [name, ms] : trials.items())
        EXPECT_LE(trials.at(chosen).get<double>(), ms.get<double>()) << name;
    EXPECT_TRUE(x.value(what + "_decided", false));
    return chosen;
}

// The nested loop's strip order under auto: timed once per scene and settings, in both orders,
// the faster kept and said; the frame is the weighted megakernel's either way.
TEST(Persistent, AutoScheduleTimesTheNestedLoopsStripOrders) {
    Scene scene = load("empty");  // every warp's lanes busy: the nested loop
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    RenderOptions o = weighted(scene, 2, 1);
    o.width = 64;
    o.height = 32;
    setPersistentScheduleAuto(o);
    const Image first = persist.render(scene, o);
    const nlohmann::json x = persist.stats().extras;
    ASSERT_EQ(x.value("persist_schedule", ""), "nested");
    const std::string order = trialChoice(x, "persist_tile", 2);
    EXPECT_NE(persist.stats().note.find(order + " strips"), std::string::npos)
        << persist.stats().note;
    EXPECT_TRUE(sameBits(mega.render(scene, o), first));
    // The next frame keeps the order without timing again; other settings time again.
    persist.render(scene, o);
    EXPECT_FALSE(persist.stats().extras.value("persist_tile_decided", true));
    EXPECT_EQ(persist.stats().extras.value("persist_tile", ""), order);
    EXPECT_EQ(persist.stats().extras.at("persist_tile_trials_ms"), x.at("persist_tile_trials_ms"));
    o.bounces = 3;
    persist.render(scene, o);
    EXPECT_TRUE(persist.stats().extras.value("persist_tile_decided", false));
}

// Where the warps disagree, auto times the regrouped flat loop against the bounce loop once per
// scene and settings and keeps the faster; the frame is the weighted megakernel's either way. A
// bounce loop the device cannot hold (B = 16) is left out, and the regrouped loop renders.
TEST(Persistent, AutoScheduleTimesTheRegroupedAndBounceLoops) {
    Scene scene = load("spheres");
    MegakernelPipeline mega(test::device());
    PersistentPipeline persist(test::device());
    RenderOptions o = weighted(scene, 4, 1);
    o.width = 40;
    o.height = 30;
    setPersistentScheduleAuto(o);
    const Image first = persist.render(scene, o);
    const nlohmann::json x = persist.stats().extras;
    ASSERT_EQ(x.value("persist_schedule", ""), "regrouped");
    const std::string loop = trialChoice(x, "persist_loop", 2);
    ASSERT_TRUE(loop == "regrouped" || loop == "bounce") << x.dump();
    EXPECT_NE(persist.stats().note.find("the " + loop + " loop"), std::string::npos)
        << persist.stats().note;
    EXPECT_TRUE(sameBits(mega.render(scene, o), first));
    EXPECT_FALSE(x.contains("persist_loop_refused")) << x.dump();
    // The next frame keeps the loop without timing again; other settings time again.
    persist.render(scene, o);
    EXPECT_FALSE(persist.stats().extras.value("persist_loop_decided", true));
    EXPECT_EQ(persist.stats().extras.value("persist_loop", ""), loop);
    o.bounces = 3;
    persist.render(scene, o);
    EXPECT_TRUE(persist.stats().extras.value("persist_loop_decided", false));

    // At B = 16 the bounce loop's batches of twice its lanes need 2^16 rays a pixel.
    o.bounces = 16;
    const DeviceInfo& dev = test::device().device();
    const double groups = 4.0 * std::max<cl_uint>(dev.computeUnits, 1);
    const double rayBytes = groups * 2.0 * 128 * 65536 * sizeof(dev::BounceRay);
    if (rayBytes <= double(dev.maxAlloc) || persistSchedule("bounce").defaultLanes(dev) != 64)
        GTEST_SKIP() << "a buffer of " << rayBytes << " bytes fits this device";
    const Image refused = persist.render(scene, o);
    const nlohmann::json y = persist.stats().extras;
    EXPECT_EQ(y.value("persist_loop", ""), "regrouped") << y.dump();
    EXPECT_TRUE(y.at("persist_loop_trials_ms").at("bounce").is_null()) << y.dump();
    // Why, in its own words: the bounce loop's scratch refusal names the batch.
    EXPECT_EQ(
        y.at("persist_loop_refused").at("bounce").get<std::string>().rfind("the bounce loop: ", 0),
        0u)
        << y.dump();
    EXPECT_TRUE(sameBits(mega.render(scene, o), refused));
}

TEST(Persistent, AutoScheduleRefusesTheFlagsItSets) {
    Scene scene = load("spheres");
    PersistentPipeline persist(test::device());
    RenderOptions o = weighted(scene, 2, 1);
    setOption(o, "persistent-schedule", std::string("auto"));
    setOption(o, "persistent-groups", 2ll);
    try {
        persist.render(scene, o);
        ADD_FAILURE() << "no error for --persistent-schedule auto with --persistent-groups";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        EXPECT_STREQ(e.what(),
                     "--persistent-schedule auto chooses --persistent-groups itself; leave it "
                     "out or use another --persistent-schedule");
    }
}

TEST(Persistent, RefusesAdaptiveAntiAliasingAndOptionsOutOfRange) {
    Scene scene = load("spheres");
    RenderOptions o = weighted(scene, 2, 2);
    o.adaptiveAa = true;
    PersistentPipeline persist(test::device());
    try {
        persist.render(scene, o);
        ADD_FAILURE() << "no error for --adaptive";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        EXPECT_NE(std::string(e.what()).find("--adaptive"), std::string::npos) << e.what();
    }
    RenderOptions g = weighted(scene, 2, 1);
    try {
        setGroups(g, 0);
        ADD_FAILURE() << "no error for --persistent-groups 0";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--persistent-groups 0: must be in 1..64");
    }
    try {
        setSchedule(g, "lockstep");  // deleted: tied the flat loop everywhere measured
        ADD_FAILURE() << "no error for --persistent-schedule lockstep";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()).rfind("--persistent-schedule lockstep: must be ", 0), 0u)
            << e.what();
    }
    try {
        setOption(g, "persistent-lanes", 8);
        ADD_FAILURE() << "no error for --persistent-lanes 8";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--persistent-lanes 8: must be in 16..1024");
    }
}

}  // namespace
}  // namespace rt
