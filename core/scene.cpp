#include "core/scene.h"

#include <atomic>

namespace rt {

uint64_t SceneId::next() {
    static std::atomic<uint64_t> counter{0};
    return ++counter;
}

int Scene::branching() const {
    for (const dev::Material& m : materials)
        if (m.opacity < 1.f) return 2;
    return 1;
}

bool Scene::hasProcedural() const {
    for (const dev::Material& m : materials)
        if (m.pattern != RT_PATTERN_NONE) return true;
    return false;
}

long long treeNodeCount(int branching, int bounces) {
    if (branching == 1) return bounces + 1;
    long long n = 0, level = 1;
    for (int d = 0; d <= bounces; ++d, level *= branching) n += level;
    return n;
}

FrameKey::FrameKey(const Scene& s, const RenderOptions& o)
    : scene(s.id.value()),
      width(o.width),
      height(o.height),
      bounces(o.bounces),
      shadowSamples(o.shadowSamples),
      aa(o.aa),
      adaptive(o.adaptiveAa && o.aa > 1),
      robustSphere(o.robustSphere),
      watertight(o.watertight),
      offset(o.offset),
      accel(o.accel),
      memoryBudget(o.memoryBudget),
      pipelineOptions(o.pipelineOptions) {}

}  // namespace rt
