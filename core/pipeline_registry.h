// rtlab — the registry of pipelines: what a front end (CLI, viewer, sweeps, benchmarks) may know
// about a pipeline is its entry here: a name, a one-line title and description, a factory, and what
// it supports. The core declares the registry and registers only its own CPU reference; each
// pipeline folder registers itself (pipelines/registry.h holds the filled registry).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/pipeline.h"

namespace rt {

// What a pipeline honours beyond the options every pipeline takes.
struct PipelineSupport {
    bool layouts = false;     // --layout tree|weighted changes how it keeps its rays
    bool adaptiveAa = false;  // --adaptive supersamples only edges
    bool tiling = false;      // splits a frame into row tiles when its memory does not fit
    bool rowWindow = false;   // renders only RenderOptions' rows [rowBegin, rowEnd) when asked
};

struct PipelineInfo {
    std::string name;         // the --pipeline value and the sweep-row "pipeline": "mega"
    std::string title;        // one line for people, e.g. the architecture's name
    std::string description;  // what makes it different, for --help
    bool reference = false;   // the CPU oracle: compared against, never measured
    PipelineSupport supports;
    // cl is null only for the reference, which needs no device.
    std::function<std::unique_ptr<Pipeline>(ClContext* cl)> make;
};

class PipelineRegistry {
public:
    // Throws rt::Error on an empty or duplicate name: two folders may not claim one name.
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
    // Creates a pipeline by name; throws when it needs a device and cl is null.
    std::unique_ptr<Pipeline> make(const std::string& name, ClContext* cl) const;

private:
    std::vector<PipelineInfo> entries_;
};

// The CPU reference's entry (core/reference.cpp renders it); the registry lists it first.
PipelineInfo referencePipelineInfo();

}  // namespace rt
