// rtlab bench — the measurement protocol of one cell (see measure.h).
#include "bench/measure.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "core/error.h"
#include "core/version.h"

namespace rt::bench {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

namespace {

// Why a step failed, and its kind as set where it was thrown (never read from the message).
struct Failed {
    std::string error;
    FailureKind kind = FailureKind::None;
    bool empty() const { return kind == FailureKind::None; }
};

Measurement failure(const Failed& why) {
    Measurement m;
    m.error = why.error;
    m.failure = why.kind;
    return m;
}

// Runs f; a failure becomes its text and kind instead of an exception.
template <typename F>
Failed attempt(F&& f) {
    try {
        f();
        return {};
    } catch (const Error& e) {
        return {e.what(), e.kind()};
    } catch (const cl::Error& e) {
        const bool memory = e.err() == CL_OUT_OF_RESOURCES || e.err() == CL_OUT_OF_HOST_MEMORY ||
                            e.err() == CL_MEM_OBJECT_ALLOCATION_FAILURE;
        return {std::string(e.what()) + " failed with " + clErrorName(e.err()),
                memory ? FailureKind::OutOfMemory : FailureKind::OpenCl};
    } catch (const std::bad_alloc&) {
        return {"out of host memory", FailureKind::OutOfMemory};
    }
}

struct Timed {
    std::vector<double> device, wall;
    std::map<std::string, std::vector<double>> kernels;
    std::vector<std::string> kernelOrder;
};

}  // namespace

std::vector<Measurement> measureCells(ClContext& cl, const Scene& scene,
                                      const std::vector<Variant>& variants, int warmup, int repeats,
                                      bool countRays, bool keepImage, double frameCapS) {
    const size_t n = variants.size();
    std::vector<double> warmupWall(n, 0);
    std::vector<Measurement> out(n);
    std::vector<std::unique_ptr<Pipeline>> pipelines(n);
    std::vector<Timed> timed(n);
    std::vector<bool> rendered(n, false);
    auto timedOptions = [&](size_t k) {
        RenderOptions o = variants[k].options;
        o.countRays = false;
        return o;
    };
    // Program builds happen inside render(): their time is kept apart from the frames'.
    std::vector<double> programMs(n, 0);
    auto building = [&](size_t k, auto&& work) {
        double before = cl.programCounts().ms;
        struct Count {  // also when work throws
            double& into;
            const ClContext& cl;
            double before;
            ~Count() { into += cl.programCounts().ms - before; }
        } count{programMs[k], cl, before};
        return work();
    };
    // The first frame allocates the pipeline's buffers: what it adds is the pipeline's memory.
    auto render = [&](size_t k) {
        size_t before = cl.allocatedBytes();
        Image frame = building(k, [&] { return pipelines[k]->render(scene, timedOptions(k)); });
        if (!rendered[k]) out[k].deviceBytes = cl.allocatedBytes() - before;
        rendered[k] = true;
        return frame;
    };
    // A fresh pipeline per cell: its buffers are its own, so the allocation delta is its memory,
    // and a large wavefront tree does not outlive the cell. Programs stay cached in the context.
    for (size_t k = 0; k < n; ++k) {
        Failed error = attempt([&] {
            pipelines[k] = makePipeline(variants[k].pipeline, &cl);
            for (int i = 0; i < warmup; ++i) {
                render(k);
                warmupWall[k] = pipelines[k]->stats().hostMs;
            }
        });
        if (!error.empty()) {
            out[k] = failure(error);
            pipelines[k].reset();
        }
    }
    // Frames of the variants alternate (round r renders each once), so that a burst of load on
    // the machine or a clock change lands on every side of their ratios alike.
    auto capped = [&](size_t k) {
        const Timed& t = timed[k];
        if (frameCapS <= 0 || t.device.empty()) return false;
        double wall = 0;
        for (double w : t.wall) wall += w;
        return wall > frameCapS * 1e3 || warmupWall[k] > frameCapS * 1e3;
    };
    for (int r = 0; r < repeats; ++r)
        for (size_t k = 0; k < n; ++k) {
            if (!pipelines[k] || capped(k)) continue;
            Failed error = attempt([&] {
                Image frame = render(k);
                const FrameStats& s = pipelines[k]->stats();
                Timed& t = timed[k];
                t.device.push_back(s.deviceMs);
                t.wall.push_back(s.hostMs);
                for (const auto& [name, ms] : s.kernelMs) {
                    if (!t.kernels.count(name)) t.kernelOrder.push_back(name);
                    t.kernels[name].push_back(ms);
                }
                out[k].longestLaunchMs = std::max(out[k].longestLaunchMs, s.longestLaunchMs);
                if (keepImage) out[k].image = std::move(frame);  // the last timed frame
            });
            if (!error.empty()) {
                out[k] = failure(error);
                pipelines[k].reset();
            }
        }
    for (size_t k = 0; k < n; ++k) {
        if (!pipelines[k]) continue;
        Measurement& m = out[k];
        const FrameStats& s = pipelines[k]->stats();
        m.buffers = s.buffers;
        m.privateBytes = s.privateBytes;
        m.extras = s.extras;
        m.kernelResources = s.kernelResources;
        m.tiles = s.tiles;
        m.launches = s.launches;
        m.accelBuildMs = s.accel.buildMs;
        const Timed& t = timed[k];
        m.frames = int(t.device.size());
        m.frameMs = t.device;
        m.deviceMs = median(t.device);
        m.deviceMsMin = *std::min_element(t.device.begin(), t.device.end());
        m.deviceMsMax = *std::max_element(t.device.begin(), t.device.end());
        m.wallMs = median(t.wall);
        for (const std::string& name : t.kernelOrder)
            m.kernelMs.emplace_back(name, median(t.kernels.at(name)));
        if (countRays) {
            // Untimed, and with its own program (RT_COUNT_RAYS), after the timed frames.
            Failed error = attempt([&] {
                RenderOptions counting = variants[k].options;
                counting.countRays = true;
                building(k, [&] { return pipelines[k]->render(scene, counting); });
                m.rays = pipelines[k]->stats().rays;
                m.raysCounted = pipelines[k]->stats().raysCounted;
                // What needs the counts; the timed frames' extras (span_ms, idle_ms) stay,
                // since the counting frame's atomics slow it.
                for (const auto& [key, value] : pipelines[k]->stats().extras.items())
                    if (!m.extras.contains(key)) m.extras[key] = value;
            });
            if (error.empty()) deriveRayCounters(m);
        }
        m.ok = true;
        pipelines[k].reset();
    }
    for (size_t k = 0; k < n; ++k) out[k].programMs = programMs[k];
    return out;
}

Measurement measureCell(ClContext& cl, const Scene& scene, const std::string& pipeline,
                        const RenderOptions& options, int warmup, int repeats, bool countRays,
                        bool keepImage) {
    return measureCells(cl, scene, {{pipeline, options}}, warmup, repeats, countRays, keepImage)[0];
}

void deriveRayCounters(Measurement& m) {
    if (!m.raysCounted) return;
    double total = 0;
    for (uint64_t r : m.rays) total += double(r);
    if (m.deviceMs > 0) m.mrays = total / (m.deviceMs * 1e3);
}

std::string deviceSlug(const DeviceInfo& d) {
    std::string name = d.name;
    std::string platform = d.platformName;
    std::transform(platform.begin(), platform.end(), platform.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (platform.find("portable computing language") != std::string::npos ||
        platform.find("pocl") != std::string::npos)
        name = "pocl " + name;
    std::string slug;
    for (unsigned char c : name) {
        if (std::isalnum(c)) {
            slug += char(std::tolower(c));
        } else if (!slug.empty() && slug.back() != '-') {
            slug += '-';
        }
    }
    while (!slug.empty() && slug.back() == '-') slug.pop_back();
    return slug.empty() ? "unknown-device" : slug;
}

nlohmann::json deviceJson(const DeviceInfo& d) {
    return {{"device", d.name},
            {"device_slug", deviceSlug(d)},
            {"device_type", d.type},
            {"platform", d.platformName},
            {"device_version", d.version},
            {"driver", d.driver},
            {"compute_units", d.computeUnits},
            {"global_mem_bytes", d.globalMem},
            {"max_alloc_bytes", d.maxAlloc},
            {"commit", RTLAB_COMMIT}};
}

nlohmann::json sceneJson(const Scene& s) {
    size_t lights = s.lights.size();
    size_t area = std::count_if(s.lights.begin(), s.lights.end(),
                                [](const dev::Light& l) { return l.radius > 0; });
    return {{"objects", s.spheres.size() + s.planes.size() + s.triangles.size()},
            {"spheres", s.spheres.size()},
            {"planes", s.planes.size()},
            {"triangles", s.triangles.size()},
            {"meshes", s.meshes.size()},
            {"lights", lights},
            {"area_lights", area},
            {"transparent", s.hasTransparency()},
            {"cubemap", s.environment.cubemapSize > 0}};
}

}  // namespace rt::bench
