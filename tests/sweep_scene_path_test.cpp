// Where a sweep's scene names lead (bench::scenePath): a bare name is <name>.json in the scene
// folder; a file name (a model, which a scene file could not wrap without replacing its
// materials) is taken as given where it exists, else found in the scene folder, as on a GPU
// host whose scenes are in --scene-dir.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bench/sweep_runner.h"
#include "scratch_dir.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

TEST(SweepScenePath, ModelNamedInsideTheSceneFolderIsFoundThere) {
    const fs::path dir = test::scratchPath("scene-dir/");
    fs::create_directories(dir / "real");
    std::ofstream(dir / "real" / "engine.glb") << "glTF";
    EXPECT_EQ(bench::scenePath("real/engine.glb", dir), dir / "real" / "engine.glb");
    EXPECT_EQ(bench::scenePath("map/wall", dir), dir / "map/wall.json");
}

TEST(SweepScenePath, FileThatExistsAsGivenOrNowhereIsKept) {
    const fs::path dir = test::scratchPath("scene-dir/");
    // Tests run from the source root, where scenes/cornell.json is.
    EXPECT_EQ(bench::scenePath("scenes/cornell.json", dir), fs::path("scenes/cornell.json"));
    // Found nowhere: the name as given, so that the load's error names it.
    EXPECT_EQ(bench::scenePath("real/missing.glb", dir), fs::path("real/missing.glb"));
}

}  // namespace
}  // namespace rt
