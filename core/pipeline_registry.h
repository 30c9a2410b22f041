// rtlab — the registry of pipelines: what a front end (CLI, viewer, sweeps, benchmarks) may know
// about a pipeline is its entry here: a name, a one-line title and description, a factory, what
// it supports, and the options it declares for itself (core/pipeline_options.h). The core declares
// the registry and registers only its own CPU reference; each pipeline folder registers itself
// (pipelines/registry.h holds the filled registry).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/pipeline.h"
#include "core/pipeline_options.h"

namespace rt {

// What a pipeline honours beyond the options every pipeline takes.
struct PipelineSupport {
    bool adaptiveAa = false;  // --adaptive supersamples only edges
    bool tiling = false;      // splits a frame into row tiles when its memory does not fit
    bool rowWindow = false;   // renders only RenderOptions' rows [rowBegin, rowEnd) when asked
};

struct PipelineInfo {
    std::string name;         // the --pipeline value and the sweep-row "pipeline": "mega"
    std::string title;        // one line for people, e.g. the architecture's name
    std::string description;  // what makes it different, for --help
    // The design family the crossover map sets against each other, recorded in every sweep row:
    // "megakernel" (one kernel, a pixel's whole ray tree per work-item) or "wavefront" (kernels
    // per stage over rays in global memory); "selector" for one that renders with one of those,
    // chosen per scene (auto); "reference" for the CPU oracle.
    std::string family;
    bool reference = false;  // the CPU oracle: compared against, never measured
    PipelineSupport supports;
    // Options only this pipeline reads: front ends make a flag, a sweep key and their parts of
    // sweep cells from each. Every pipeline's options apply to every cell of a sweep group and
    // to every --pipeline, as shared options do; the others' pipelines ignore them.
    std::vector<PipelineOption> options;
    // The settings of its options that tests and the smoke check run one by one; empty: the
    // defaults only, as one variant named "".
    std::vector<PipelineVariant> variants;
    // Called by the command line after it applied the flags, for every pipeline: lets one
    // settle a shared option whose command-line default its own options cannot honour.
    // launchCapGiven says whether --max-launch-ms was given (else it holds the CLI default).
    std::function<void(RenderOptions& options, bool launchCapGiven)> settleDefaults;
    // Whether it renders this frame on this device in one piece (no row tiles); unset: always.
    // The choosers ask it (auto/) without naming the pipeline's types.
    std::function<bool(const Scene& scene, const RenderOptions& options, const DeviceInfo& device)>
        fitsOnePiece;
    // cl is null only for the reference, which needs no device.
    std::function<std::unique_ptr<Pipeline>(ClContext* cl)> make;
};

// A pipeline in one of its variants, as tests and the smoke check run it.
struct PipelineVariantRun {
    std::string pipeline;     // the registered name: "mega"
    PipelineVariant variant;  // {"", {}} for a pipeline without variants
    std::string name;         // for messages: "mega-weighted", or "wave" without variants
    // Sets the variant's option values in `options`.
    void apply(RenderOptions& options) const { options.pipelineOptions.setAll(variant.values); }
};

class PipelineRegistry {
  public:
    // Throws rt::Error on an empty or duplicate name: two folders may not claim one name, nor
    // two pipelines one option name, sweep key or cell tag.
    void add(PipelineInfo info);
    const std::vector<PipelineInfo>& all() const { return entries_; }
    const PipelineInfo* find(const std::string& name) const;
    // Throws rt::Error (invalid_option) "--pipeline NAME: must be one of cpu, mega, ...".
    const PipelineInfo& get(const std::string& name) const;
    // Names in registration order; without the reference when devicesOnly is set.
    std::vector<std::string> names(bool devicesOnly = false) const;
    // "cpu, mega, wave": for error messages and help.
    std::string joinedNames(bool devicesOnly = false) const;
    // One line per pipeline, "  NAME  TITLE: DESCRIPTION", for --help.
    std::string help() const;
    // Every pipeline's declared options, in registration order (the order of cell keys).
    std::vector<const PipelineOption*> options() const;
    // Every pipeline in each of its variants, in registration order; without the reference
    // when devicesOnly is set.
    std::vector<PipelineVariantRun> variants(bool devicesOnly = false) const;
    // The option declared with this sweep-file key, or null.
    const PipelineOption* findSweepOption(const std::string& sweepKey) const;
    // Creates a pipeline by name; throws when it needs a device and cl is null.
    std::unique_ptr<Pipeline> make(const std::string& name, ClContext* cl) const;

  private:
    std::vector<PipelineInfo> entries_;
};

// The CPU reference's entry (core/reference.cpp renders it); the registry lists it first.
PipelineInfo referencePipelineInfo();
// The independent accuracy oracle's entry (renderOracle), listed second.
PipelineInfo oraclePipelineInfo();

}  // namespace rt
