// rtlab — the filled registry (see registry.h).
#include "pipelines/registry.h"

namespace rt {

const PipelineRegistry& pipelineRegistry() {
    // Filled in place and never freed: an entry may keep a reference to the registry it was
    // added to (auto makes the pipelines it chooses between through it).
    static const PipelineRegistry* registry = [] {
        auto* r = new PipelineRegistry;
        r->add(referencePipelineInfo());
        r->add(oraclePipelineInfo());
        registerPipelineFolders(*r);
        return r;
    }();
    return *registry;
}

std::unique_ptr<Pipeline> makePipeline(const std::string& name, ClContext* cl) {
    return pipelineRegistry().make(name, cl);
}

const PipelineInfo& pipelineInfo(const std::string& name) { return pipelineRegistry().get(name); }

}  // namespace rt
