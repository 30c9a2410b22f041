// libFuzzer target: OBJ models (core/obj_loader.cpp) through the bare-OBJ scene wrapper,
// seeded with tests/data/**/*.obj and Debian's assimp-testmodels OBJ files (scripts/fuzz).
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    rt::fuzz::loadAndBuild(rt::fuzz::writeInput("model.obj", data, size));
    return 0;
}
