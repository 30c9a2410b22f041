// rtlab — the megakernel's own option (--layout), declared in its registry entry
// (core/pipeline_options.h) and read back here, typed, from RenderOptions::pipelineOptions.
// Front ends know it only through the declaration.
#pragma once

#include <string>
#include <vector>

#include "core/pipeline_options.h"
#include "core/scene.h"

namespace rt {

struct DeviceInfo;  // core/cl_runtime.h

// How a work-item keeps its rays in private memory: the full ray tree of the report (N nodes),
// or a stack of pending rays, each with the weight it adds to its pixel (B * (C - 1) + 1).
enum class MegaLayout { Tree, Weighted };

// The declarations, in the order cell keys list them.
std::vector<PipelineOption> megakernelOptions();
// The settings tests and the smoke check run one by one: each layout.
std::vector<PipelineVariant> megakernelVariants();

MegaLayout megaLayout(const RenderOptions& options);
void setMegaLayout(RenderOptions& options, MegaLayout layout);
// --max-registers: 0 for the compiler's choice.
int megaMaxRegisters(const RenderOptions& options);
void setMegaMaxRegisters(RenderOptions& options, int registers);
// The name as --layout takes it: tree, weighted.
const char* megaLayoutName(MegaLayout layout);

// A cap on the registers a work-item for NVIDIA's compiler (-cl-nv-maxrregcount), as a pipeline
// option: `name` is the flag without its dashes, `who` the pipeline as its help names it, `hint`
// what to change with it. The megakernel's is --max-registers, the persistent megakernel's
// --persistent-max-registers.
PipelineOption registerCapOption(const std::string& name, const std::string& who,
                                 const std::string& hint, const std::string& cellTag);
// The build options for a cap of `registers` (0: none) on `device`: the NVIDIA flag, or nothing
// elsewhere.
std::vector<std::string> registerCapBuildOptions(long long registers, const DeviceInfo& device);

}  // namespace rt
