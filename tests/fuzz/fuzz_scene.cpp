// libFuzzer target: JSON scene files (core/scene_loader.cpp), seeded with scenes/*.json and
// tests/data/bad_scenes (scripts/fuzz). Scenes may name the model m.obj beside them.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    rt::fuzz::loadAndBuild(rt::fuzz::writeInput("scene.json", data, size));
    return 0;
}
