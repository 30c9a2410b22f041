// rtlab — the filled registry (see registry.h).
#include "pipelines/registry.h"

namespace rt {

const PipelineRegistry& pipelineRegistry() {
    static const PipelineRegistry registry = [] {
        PipelineRegistry r;
        r.add(referencePipelineInfo());
        r.add(oraclePipelineInfo());
        registerPipelineFolders(r);
        return r;
    }();
    return registry;
}

std::unique_ptr<Pipeline> makePipeline(const std::string& name, ClContext* cl) {
    return pipelineRegistry().make(name, cl);
}

const PipelineInfo& pipelineInfo(const std::string& name) { return pipelineRegistry().get(name); }

}  // namespace rt
