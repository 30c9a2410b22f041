// rtlab bench — the GPU smoke check (see smoke.h).
#include "bench/smoke.h"

#include <map>
#include <memory>
#include <optional>

#include "bench/frame_check.h"
#include "bench/measure.h"
#include "bench/sweep_runner.h"
#include "bench/watchdog.h"
#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/version.h"
#include "pipelines/registry.h"

namespace rt::bench {

namespace {

// The agreement tests/accel_test.cpp asks of two structures: another traversal order may only
// change which of two equally near primitives wins, or let a grazing ray through a slab test.
constexpr double kPixelTolerance = 1.0 / 255.0;
constexpr double kMinFractionWithin = 0.999;
constexpr double kMaxMeanAbs = 0.1 / 255.0;

struct Frame {
    bool ok = false;
    bool timedOut = false;
    bool deviceStuck = false;  // timed out outside a program build
    std::string error;
    double ms = 0;
    Image image;
};

}  // namespace

SmokeOptions defaultSmokeOptions() {
    SmokeOptions o;
    o.scenes = {"empty", "spheres", "shadows", "cornell", "mesh", "envmap", "divergence"};
    for (const char* spd : {"balls", "gears", "mount", "rings", "teapot", "tetra", "tree"})
        o.spotScenes.push_back(std::string("spd/") + spd + ".nff");
    o.sizes = {"160x90", "1920x1080"};
    o.pipelines = pipelineRegistry().names(true);
    o.accels = {"none", "bv", "grid", "bvh", "wide", "cwbvh"};
    o.cellTimeoutS = kDefaultCellTimeoutS;
    return o;
}

SmokeSummary runSmoke(const SmokeOptions& options, std::FILE* out) {
    struct Unit {
        std::string scene;
        RenderOptions::Accel accel;
        bool accelApplies;
        bool spot = false;  // the first size only (SmokeOptions::spotScenes)
    };
    std::map<std::string, std::shared_ptr<const Scene>> scenes;
    std::vector<Unit> units;
    for (const std::string& name : options.scenes) {
        auto scene = std::make_shared<const Scene>(
            loadScene(scenePath(name, options.sceneDir), options.readImage));
        scenes[name] = scene;
        bool applies = !scene->spheres.empty() || !scene->triangles.empty();
        if (!applies) {
            units.push_back({name, scene->defaults.accel, false});
            continue;
        }
        for (const std::string& a : options.accels) units.push_back({name, parseAccel(a), true});
    }
    for (const std::string& name : options.spotScenes) {
        auto scene = std::make_shared<const Scene>(
            loadScene(scenePath(name, options.sceneDir), options.readImage));
        scenes[name] = scene;
        units.push_back({name, RenderOptions::Accel::Bvh, true, true});
    }
    std::vector<std::pair<int, int>> sizes;
    for (const std::string& s : options.sizes) {
        int w = 0, h = 0;
        if (std::sscanf(s.c_str(), "%dx%d", &w, &h) != 2 || w < 1 || h < 1)
            throw Error("--sizes " + s + ": expected WIDTHxHEIGHT, both at least 1");
        sizes.emplace_back(w, h);
    }
    // Each pipeline asked for in each of its variants (PipelineInfo::variants); the first is
    // the reference frame's.
    std::vector<PipelineVariantRun> variants;
    const std::vector<PipelineVariantRun> all = pipelineRegistry().variants(true);
    for (const std::string& p : options.pipelines) {
        if (pipelineInfo(p).reference) continue;
        for (const PipelineVariantRun& v : all)
            if (v.pipeline == p) variants.push_back(v);
    }

    auto cl = std::make_shared<ClContext>(selectDevice(options.device), options.sources);
    std::fprintf(out, "smoke: %zu scene(s) x %zu size(s) x %zu variant(s) on %s, commit %s%s\n",
                 options.scenes.size() + options.spotScenes.size(), sizes.size(), variants.size(),
                 cl->device().label().c_str(), RTLAB_COMMIT,
                 options.shard.whole() ? "" : (", shard " + options.shard.str()).c_str());
    std::fflush(out);
    SmokeSummary summary;

    // One frame under the cell time limit. A stuck compiler leaves its context behind and the
    // check goes on in a new one; a stuck device stops it (what runs after could not be trusted).
    auto render = [&](const std::shared_ptr<const Scene>& scene, const std::string& pipeline,
                      const RenderOptions& o) {
        Frame f;
        std::shared_ptr<ClContext> ctx = cl;
        auto got = withinSeconds(options.cellTimeoutS, [ctx, scene, pipeline, o] {
            return measureCells(*ctx, *scene, {{pipeline, o}}, 0, 1, false, true)[0];
        });
        if (!got) {
            f.timedOut = true;
            std::string compiling = ctx->building();
            char head[96];
            std::snprintf(head, sizeof head,
                          "timeout: not done after %g s: ", options.cellTimeoutS);
            f.error = head + (compiling.empty()
                                  ? std::string("the device or its driver did not return")
                                  : "the OpenCL compiler did not finish building " + compiling);
            f.deviceStuck = compiling.empty();
            if (!f.deviceStuck) cl = std::make_shared<ClContext>(ctx->device(), options.sources);
            return f;
        }
        f.ok = got->ok;
        f.error = got->error;
        f.ms = got->deviceMs;
        f.image = std::move(got->image);
        return f;
    };

    // The megakernel's frame (tree layout, the scene's own structure) per scene and size.
    std::map<std::string, Frame> references;
    for (size_t u = 0; u < units.size(); ++u) {
        if (int(u % size_t(options.shard.count)) != options.shard.index) continue;
        const Unit& unit = units[u];
        const std::shared_ptr<const Scene>& scene = scenes.at(unit.scene);
        for (auto [w, h] : sizes) {
            if (unit.spot && std::make_pair(w, h) != sizes.front()) continue;
            RenderOptions base = scene->defaults;
            base.width = w;
            base.height = h;
            std::string where = unit.scene + " " + std::to_string(w) + "x" + std::to_string(h);
            std::string refKey = where;
            for (const PipelineVariantRun& v : variants) {
                RenderOptions o = base;
                v.apply(o);
                if (unit.accelApplies) o.accel = unit.accel;
                std::string label = where + " " + v.pipeline + " " +
                                    (v.variant.name.empty() ? "-" : v.variant.name) + " " +
                                    (unit.accelApplies ? accelName(unit.accel) : "-");
                ++summary.cells;
                if (summary.stopped) {
                    ++summary.failed;
                    std::fprintf(out, "FAIL  %s  not run: an earlier cell left the device stuck\n",
                                 label.c_str());
                    continue;
                }
                bool isReference =
                    v.name == variants.front().name && o.accel == scene->defaults.accel;
                Frame f = render(scene, v.pipeline, o);
                if (isReference) references[refKey] = f;
                summary.stopped = f.deviceStuck;
                std::string detail;
                bool pass = f.ok;
                if (!f.ok) {
                    detail = f.error;
                } else if (long long bad = nonFinitePixels(f.image); bad > 0) {
                    pass = false;
                    detail = std::to_string(bad) + " pixels NaN or infinite";
                } else if (isReference) {
                    detail = "the reference frame";
                } else {
                    auto ref = references.find(refKey);
                    if (ref == references.end()) {
                        RenderOptions r = base;
                        variants.front().apply(r);
                        ref =
                            references.emplace(refKey, render(scene, variants.front().pipeline, r))
                                .first;
                        summary.stopped = summary.stopped || ref->second.deviceStuck;
                    }
                    if (!ref->second.ok) {
                        pass = false;
                        detail = "no reference frame: " + ref->second.error;
                    } else {
                        FrameAgreement d =
                            compareFrames(ref->second.image, f.image, kPixelTolerance);
                        pass = d.fractionWithin >= kMinFractionWithin && d.meanAbs <= kMaxMeanAbs;
                        char buf[200];
                        std::snprintf(buf, sizeof buf,
                                      "against %s %s %s: max |d| %.3g, %.3f%% of pixels within "
                                      "1/255, mean |d| %.2g",
                                      variants.front().pipeline.c_str(),
                                      variants.front().variant.name.empty()
                                          ? "-"
                                          : variants.front().variant.name.c_str(),
                                      unit.accelApplies ? accelName(scene->defaults.accel) : "-",
                                      d.maxAbs, 100 * d.fractionWithin, d.meanAbs);
                        detail = buf;
                    }
                }
                ++(pass ? summary.passed : summary.failed);
                if (f.ok)
                    std::fprintf(out, "%s  %s  %.3f ms  %s\n", pass ? "PASS" : "FAIL",
                                 label.c_str(), f.ms, detail.c_str());
                else
                    std::fprintf(out, "FAIL  %s  %s\n", label.c_str(), detail.c_str());
                std::fflush(out);
            }
        }
    }
    return summary;
}

}  // namespace rt::bench
