// libFuzzer target: NFF files (core/nff_loader.cpp) through loadScene, seeded with the SPD scenes
// (scenes/spd/*.nff, cut to their first 64 KiB by -max_len) and tests/data/bad_nff (scripts/fuzz).
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    rt::fuzz::loadAndBuild(rt::fuzz::writeInput("scene.nff", data, size));
    return 0;
}
