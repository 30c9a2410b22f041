// rtlab — `--pipeline auto` (auto.h): the choice, the trial frames and the delegation.
#include "auto/auto.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/pipeline_registry.h"

namespace rt {

namespace {

enum class AutoChoice { Predict, Lanes, Measure };
enum class AutoRule { Device, Gpu, Cpu };

const PipelineOption& choiceOption() {
    static const PipelineOption o{
        .name = "auto-choice",
        .type = PipelineOption::Type::Choice,
        .help =
            "Auto: how it picks a design for a scene: predict (the predictor's busy lanes "
            "name the kind of design, two trial frames each pick within it), lanes (the "
            "predictor alone, no trial frames) or measure (trial frames of every design) "
            "[predict]",
        .defaultValue = std::string("predict"),
        .choices = {"predict", "lanes", "measure"},
        .sweepKey = "auto-choice",
        .cellTag = "A",
        .label = "auto by {}",
    };
    return o;
}

const PipelineOption& ruleOption() {
    static const PipelineOption o{
        .name = "auto-rule",
        .type = PipelineOption::Type::Choice,
        .help =
            "Auto, predict: whose fitted rule decides: the device's kind, gpu (the H200 "
            "map's) or cpu (the PoCL map's) [device]",
        .defaultValue = std::string("device"),
        .choices = {"device", "gpu", "cpu"},
        .sweepKey = "auto-rule",
        .cellTag = "R",
        .label = "{} rule",
    };
    return o;
}

std::string format(const char* fmt, double a, double b = 0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, fmt, a, b);
    return buf;
}

}  // namespace

std::string AutoDesign::name() const { return pipeline == "mega" ? "mega-" + layout : pipeline; }

AutoKind chooseKind(const LaneEstimate& e, const AutoContext& c) {
    const std::string lanes = format("%.1f busy lanes of %.0f", e.busyLanes, double(e.lanes));
    const std::string fitting = c.treeFits ? "tree" : "weighted";
    if (c.adaptive)
        return {{{"mega", fitting, ""}}, "adaptive anti-aliasing: only the megakernel has it"};
    if (!c.gpuRule)
        return {{{"mega", fitting, ""}},
                "a CPU runs work-items without lock-step lanes: the queue wavefront never won "
                "the CPU map, where the megakernel ties with or beats the others"};
    if (std::abs(e.busyLanes - kQueueBelowLanes) < kUncertainLanes) {
        // Too close to the threshold to call: every design in one piece is timed, the
        // predictor's side first (the one `lanes` takes without trial frames).
        const bool queueSide = e.busyLanes < kQueueBelowLanes;
        AutoKind k{{},
                   lanes + format(" (within %.1f of %.1f): too close to call", kUncertainLanes,
                                  kQueueBelowLanes)};
        if (queueSide) k.designs.push_back({"queue", "weighted", ""});
        k.designs.push_back({"mega", "weighted", ""});
        if (c.waveFits) k.designs.push_back({"wave", "weighted", ""});
        k.designs.push_back({"persist", "weighted", ""});
        if (!queueSide) k.designs.push_back({"queue", "weighted", ""});
        return k;
    }
    if (e.busyLanes < kQueueBelowLanes)
        return {{{"queue", "weighted", ""}, {"persist", "weighted", ""}},
                lanes + format(" (below %.1f): neighbouring pixels' trees disagree, so a "
                               "design that keeps lanes busy: compacted queues or "
                               "regrouped persistent threads",
                               kQueueBelowLanes)};
    AutoKind k{{{"mega", "weighted", ""}},
               lanes + format(" (at least %.1f): one tree a work-item", kQueueBelowLanes)};
    if (c.waveFits)
        k.designs.push_back({"wave", "weighted", ""});
    else
        k.reason += "; the tree wavefront's tree would need row tiles";
    k.designs.push_back({"persist", "weighted", ""});
    return k;
}

struct AutoPipeline::Impl {
    Impl(ClContext& cl, const PipelineRegistry& registry) : cl(cl), registry(registry) {}

    ClContext& cl;
    const PipelineRegistry& registry;
    std::map<std::string, std::unique_ptr<Pipeline>> pipelines;  // made by the registry, kept
    // The predictor's estimate of the scene the choice was last made for, which the persistent
    // megakernel's own schedule choice reuses.
    std::optional<LaneEstimate> estimate;
    double estimateMs = 0;
    FrameKey key;
    AutoDesign design;
    nlohmann::json extras;  // what the decision found, carried into every frame's statistics
    bool decided = false;

    Pipeline& pipeline(const std::string& name, const Pipeline::Progress& progress) {
        std::unique_ptr<Pipeline>& p = pipelines[name];
        if (!p) p = registry.make(name, &cl);
        p->setProgress(progress);
        return *p;
    }

    // Sets `pipeline`'s option `option` to `value` in `o`, as its registry entry declares it.
    void setOption(RenderOptions& o, const std::string& pipeline, const std::string& option,
                   const std::string& value) const {
        for (const PipelineOption& declared : registry.get(pipeline).options)
            if (declared.name == option) return declared.set(o.pipelineOptions, value);
        throw Error("auto: " + pipeline + " has no option --" + option);
    }

    // The options a design renders with: the megakernel in its layout; the persistent
    // megakernel in its variant "auto" (it chooses its own schedule), from the estimate auto made
    // when it made one.
    RenderOptions optionsFor(const Scene& scene, const RenderOptions& o, const AutoDesign& d) {
        RenderOptions out = o;
        if (d.pipeline == "mega") setOption(out, "mega", "layout", d.layout);
        if (d.pipeline == "persist") {
            for (const PipelineVariant& v : registry.get("persist").variants)
                if (v.name == "auto") out.pipelineOptions.setAll(v.values);
            const auto made = pipelines.find("persist");
            if (estimate && made != pipelines.end() && made->second)
                made->second->useLaneEstimate(scene, out, *estimate, estimateMs);
        }
        return out;
    }

    AutoContext context(const Scene& scene, const RenderOptions& o, AutoRule rule) const {
        AutoContext c;
        const DeviceInfo& dev = cl.device();
        c.gpuRule = rule == AutoRule::Gpu || (rule == AutoRule::Device && dev.isGpu());
        c.adaptive = o.adaptiveAa && o.aa > 1;
        const int C = scene.branching();
        c.treeFits = treePrivateBytes(C, o.bounces, dev::nodeBytes(scene.lights.size())) <=
                     kPrivateTreeLimit;
        const PipelineInfo& wave = registry.get("wave");
        c.waveFits = !wave.fitsOnePiece || wave.fitsOnePiece(scene, o, dev);
        return c;
    }
};

AutoPipeline::AutoPipeline(ClContext& cl, const PipelineRegistry& registry)
    : impl_(std::make_unique<Impl>(cl, registry)) {}
AutoPipeline::~AutoPipeline() = default;

Image AutoPipeline::render(const Scene& scene, const RenderOptions& o) {
    Impl& m = *impl_;
    const Progress forward = [this](long long done, long long total) {
        reportProgress(done, total);
    };
    const FrameKey key(scene, o);
    const bool decideNow = !m.decided || !(m.key == key);
    Image image;
    bool rendered = false;
    if (decideNow) {
        m.decided = false;
        m.extras = nlohmann::json::object();
        m.estimate.reset();
        const auto choice = AutoChoice(choiceOption().index(o.pipelineOptions));
        const auto rule = AutoRule(ruleOption().index(o.pipelineOptions));
        const AutoContext context = m.context(scene, o, rule);
        std::vector<AutoDesign> candidates;
        std::string reason;
        if (choice == AutoChoice::Measure) {
            // Every design that can render the frame in one piece.
            if (context.treeFits) candidates.push_back({"mega", "tree", ""});
            candidates.push_back({"mega", "weighted", ""});
            if (!context.adaptive) {
                if (context.waveFits) candidates.push_back({"wave", "weighted", ""});
                candidates.push_back({"queue", "weighted", ""});
                candidates.push_back({"persist", "weighted", ""});
            }
        } else {
            const auto start = std::chrono::steady_clock::now();
            m.estimate = estimateBusyLanes(scene, o);
            m.estimateMs =
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count();
            m.extras["auto_predict_ms"] = m.estimateMs;
            m.extras["auto_busy_lanes"] = m.estimate->busyLanes;
            AutoKind kind = chooseKind(*m.estimate, context);
            reason = kind.reason;
            candidates = std::move(kind.designs);
            if (choice == AutoChoice::Lanes) candidates.resize(1);
        }
        if (candidates.size() == 1) {
            m.design = candidates.front();
            m.design.reason = reason;
        } else {
            // Two frames each (the first may pay for first-launch work), the faster compared.
            double best = std::numeric_limits<double>::infinity();
            std::string times;
            nlohmann::json trials = nlohmann::json::object();
            for (const AutoDesign& d : candidates) {
                Pipeline& p = m.pipeline(d.pipeline, forward);
                const RenderOptions options = m.optionsFor(scene, o, d);
                double ms = std::numeric_limits<double>::infinity();
                Image frame;
                for (int i = 0; i < 2; ++i) {
                    frame = p.render(scene, options);
                    ms = std::min(ms, p.stats().deviceMs);
                }
                trials[d.name()] = ms;
                times += (times.empty() ? "" : ", ") + d.name() + format(" %.3f ms", ms);
                if (ms < best) {
                    best = ms;
                    m.design = d;
                    image = std::move(frame);
                    stats_ = p.stats();
                }
            }
            m.design.reason = (reason.empty() ? "" : reason + "; ") +
                              "the fastest of 2 trial frames each: " + times;
            m.extras["auto_trials_ms"] = trials;
            rendered = true;
        }
        m.key = key;
        m.decided = true;
    }
    const AutoDesign& d = m.design;
    if (!rendered) {
        Pipeline& p = m.pipeline(d.pipeline, forward);
        image = p.render(scene, m.optionsFor(scene, o, d));
        stats_ = p.stats();
    }
    stats_.extras["auto_design"] = d.name();
    stats_.extras["auto_reason"] = d.reason;
    stats_.extras["auto_decided"] = decideNow;
    for (auto& [k, v] : m.extras.items()) stats_.extras[k] = v;
    // The chosen design's own note (the persistent megakernel's schedule) after auto's.
    const std::string designNote = stats_.note;
    stats_.note = "auto: " + d.name() + ": " + d.reason;
    if (!designNote.empty()) stats_.note += "; " + designNote;
    return image;
}

void registerAutoPipeline(PipelineRegistry& registry) {
    PipelineInfo p;
    p.name = "auto";
    p.title = "auto (chooses a design per scene)";
    p.family = "selector";
    p.description =
        "renders with the design the predictor (rtlab predict) and trial frames pick for the "
        "scene; --auto-choice says how, --stats and a line on stderr say which and why";
    p.supports = {.adaptiveAa = true, .tiling = false, .rowWindow = true};
    p.options = {choiceOption(), ruleOption()};
    // The registry being filled, which lives as long as the pipelines it makes.
    p.make = [&registry](ClContext* cl) { return std::make_unique<AutoPipeline>(*cl, registry); };
    registry.add(std::move(p));
}

}  // namespace rt
