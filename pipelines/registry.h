// rtlab — the filled pipeline registry that every front end uses: the CPU reference, then each
// pipeline folder in the order the build lists them (CMakeLists.txt, add_subdirectory). Front ends
// link rtlab_pipelines and never name a pipeline themselves.
#pragma once

#include <memory>
#include <string>

#include "core/pipeline_registry.h"

namespace rt {

// Built on first use; the same object for the life of the process.
const PipelineRegistry& pipelineRegistry();

// Shorthands for pipelineRegistry().make(...) and .get(...).
std::unique_ptr<Pipeline> makePipeline(const std::string& name, ClContext* cl);
const PipelineInfo& pipelineInfo(const std::string& name);

// Calls every folder's registration function (generated/registry_list.cpp, written by CMake).
void registerPipelineFolders(PipelineRegistry& registry);

}  // namespace rt
