// libFuzzer target: glTF 2.0 and PLY models (core/model_loader.cpp, through assimp) by way of the
// bare-model scene wrapper, seeded with tests/data/models, tests/data/bad_models and Debian's
// assimp-testmodels glTF2 and PLY files (scripts/fuzz). The input's first bytes pick the name it
// is written under, so that one corpus reaches all three readers: "ply" a .ply file, "glTF" a
// .glb file, anything else a .gltf file.
#include <cstring>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const char* name = "model.gltf";
    if (size >= 3 && std::memcmp(data, "ply", 3) == 0) name = "model.ply";
    if (size >= 4 && std::memcmp(data, "glTF", 4) == 0) name = "model.glb";
    rt::fuzz::loadAndBuild(rt::fuzz::writeInput(name, data, size));
    return 0;
}
