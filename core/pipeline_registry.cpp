// rtlab — the pipeline registry (see pipeline_registry.h) and the CPU reference's entry.
#include "core/pipeline_registry.h"

#include <algorithm>
#include <chrono>

#include "core/error.h"
#include "core/reference.h"

namespace rt {

void PipelineRegistry::add(PipelineInfo info) {
    if (info.name.empty() || !info.make)
        throw Error("a pipeline registered without a name or factory");
    if (info.family.empty())
        throw Error("pipeline '" + info.name + "' registered without a family (megakernel, " +
                    "wavefront, ...: PipelineInfo::family)");
    if (find(info.name)) throw Error("pipeline '" + info.name + "' is registered twice");
    std::vector<const PipelineOption*> known = options();
    for (const PipelineOption& o : info.options) {
        if (o.name.empty() || o.sweepKey.empty() || o.cellTag.empty() ||
            o.label.find("{}") == std::string::npos)
            throw Error("pipeline '" + info.name +
                        "' declares an option without a name, sweep "
                        "key, cell tag or label with {}");
        for (const PipelineOption* k : known)
            if (k->name == o.name || k->sweepKey == o.sweepKey || k->cellTag == o.cellTag)
                throw Error("pipeline '" + info.name + "' declares option " + o.name +
                            ", whose name, sweep key or cell tag another option has");
        known.push_back(&o);
    }
    entries_.push_back(std::move(info));
}

const PipelineInfo* PipelineRegistry::find(const std::string& name) const {
    for (const PipelineInfo& p : entries_)
        if (p.name == name) return &p;
    return nullptr;
}

const PipelineInfo& PipelineRegistry::get(const std::string& name) const {
    if (const PipelineInfo* p = find(name)) return *p;
    throw Error("--pipeline " + name + ": must be one of " + joinedNames(),
                FailureKind::InvalidOption);
}

std::vector<std::string> PipelineRegistry::names(bool devicesOnly) const {
    std::vector<std::string> out;
    for (const PipelineInfo& p : entries_)
        if (!devicesOnly || !p.reference) out.push_back(p.name);
    return out;
}

std::string PipelineRegistry::joinedNames(bool devicesOnly) const {
    std::string out;
    for (const std::string& n : names(devicesOnly)) out += (out.empty() ? "" : ", ") + n;
    return out;
}

std::string PipelineRegistry::help() const {
    size_t width = 0;
    for (const PipelineInfo& p : entries_) width = std::max(width, p.name.size());
    std::string out;
    for (const PipelineInfo& p : entries_)
        out += "  " + p.name + std::string(width - p.name.size() + 2, ' ') + p.title + ": " +
               p.description + "\n";
    return out;
}

std::vector<const PipelineOption*> PipelineRegistry::options() const {
    std::vector<const PipelineOption*> out;
    for (const PipelineInfo& p : entries_)
        for (const PipelineOption& o : p.options) out.push_back(&o);
    return out;
}

std::vector<PipelineVariantRun> PipelineRegistry::variants(bool devicesOnly) const {
    std::vector<PipelineVariantRun> out;
    for (const PipelineInfo& p : entries_) {
        if (devicesOnly && p.reference) continue;
        if (p.variants.empty()) out.push_back({p.name, {}, p.name});
        for (const PipelineVariant& v : p.variants)
            out.push_back({p.name, v, v.name.empty() ? p.name : p.name + "-" + v.name});
    }
    return out;
}

const PipelineOption* PipelineRegistry::findSweepOption(const std::string& sweepKey) const {
    for (const PipelineOption* o : options())
        if (o->sweepKey == sweepKey) return o;
    return nullptr;
}

std::unique_ptr<Pipeline> PipelineRegistry::make(const std::string& name, ClContext* cl) const {
    const PipelineInfo& info = get(name);
    if (!info.reference && !cl) throw Error("pipeline " + name + " needs an OpenCL device");
    return info.make(cl);
}

namespace {

// The CPU reference (the renderers' method in double) or the independent oracle.
class CpuPipeline : public Pipeline {
  public:
    explicit CpuPipeline(bool oracle) : oracle_(oracle) {}
    const char* name() const override { return oracle_ ? "oracle" : "cpu"; }
    Image render(const Scene& scene, const RenderOptions& options) override {
        checkOptions(scene, options);
        stats_ = {};
        auto t0 = std::chrono::steady_clock::now();
        Image image = oracle_ ? renderOracle(scene, options, 0, progress_)
                              : renderReference(scene, options, 0, progress_);
        stats_.hostMs =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count();
        return image;
    }

  private:
    bool oracle_;
};

}  // namespace

PipelineInfo referencePipelineInfo() {
    PipelineInfo p;
    p.name = "cpu";
    p.title = "CPU reference";
    p.family = "reference";
    p.description =
        "the same algorithm and method (intersection tests, --offset) in double precision on the "
        "host; shares the renderers' mistakes, so it is not the accuracy oracle";
    p.reference = true;
    p.supports = {.adaptiveAa = true, .tiling = false, .rowWindow = false};
    p.make = [](ClContext*) { return std::make_unique<CpuPipeline>(false); };
    return p;
}

PipelineInfo oraclePipelineInfo() {
    PipelineInfo p = referencePipelineInfo();
    p.name = "oracle";
    p.title = "Independent oracle";
    p.description =
        "the accuracy oracle: the algorithm in double precision with no offset rule, its rays "
        "never offered the flat primitive (or convex sphere) they leave (core/SHADING.md 3)";
    p.make = [](ClContext*) { return std::make_unique<CpuPipeline>(true); };
    return p;
}

}  // namespace rt
