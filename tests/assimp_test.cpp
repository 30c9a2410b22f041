// The assimp-testmodels sweeps: every OBJ file under /usr/share/assimp/models, and every
// glTF 2.0 (.gltf, .glb) and PLY file under its glTF2/ and PLY/ folders (Debian's
// assimp-testmodels, scripts/setup installs it), valid or broken, either renders as a bare-model
// scene on the CPU reference and the megakernel without a non-finite pixel, or is rejected with
// one line naming the file. tests/obj_loader_test.cpp and tests/model_loader_test.cpp check
// known values of some.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "pipelines/registry.h"
#include "test_device.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

// The files under `root` whose lower-case extension is one of `extensions`, sorted.
std::vector<fs::path> corpusFiles(const fs::path& root,
                                  std::initializer_list<const char*> extensions) {
    std::vector<fs::path> files;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::end(it);
         it.increment(ec)) {
        std::string ext = it->path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        bool wanted = false;
        for (const char* e : extensions) wanted |= ext == e;
        if (wanted && it->is_regular_file()) files.push_back(it->path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

struct SweepCounts {
    int rendered = 0, rejected = 0;
};

// Loads every file as a bare model; renders what loads at 16x12 on the CPU reference and the
// megakernel, and checks that what does not fails with one line that names the file first.
SweepCounts sweep(const std::vector<fs::path>& files) {
    SweepCounts counts;
    int& rendered = counts.rendered;
    int& rejected = counts.rejected;
    for (const fs::path& file : files) {
        SCOPED_TRACE(file.string());
        Scene scene;
        try {
            scene = loadScene(file);
        } catch (const Error& e) {
            std::string msg = e.what();
            EXPECT_EQ(msg.rfind(file.string(), 0), 0u) << "names the file first: " << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
            EXPECT_GT(msg.size(), file.string().size() + 4) << "gives a reason: " << msg;
            ++rejected;
            continue;
        }
        RenderOptions o = scene.defaults;
        o.width = 16;
        o.height = 12;
        o.bounces = 2;
        for (std::string k : {"cpu", "mega"}) {
            Image img = makePipeline(k, &test::device())->render(scene, o);
            EXPECT_EQ(img.rgb.size(), 16u * 12u * 3u);
            size_t bad = 0;
            for (float v : img.rgb) bad += !std::isfinite(v);
            EXPECT_EQ(bad, 0u) << k << ": non-finite channels";
        }
        EXPECT_GT(scene.triangles.size(), 0u);
        ++rendered;
    }
    return counts;
}

#define RTLAB_REQUIRE_CORPUS(files)                                                      \
    do {                                                                                 \
        if ((files).empty()) {                                                           \
            if (rt::test::underCi())                                                     \
                FAIL() << "assimp-testmodels not installed (scripts/setup installs it)"; \
            GTEST_SKIP() << "assimp-testmodels not installed (scripts/setup)";           \
        }                                                                                \
    } while (0)

TEST(AssimpSweep, EveryObjRendersOrFailsWithOneClearLine) {
    const std::vector<fs::path> files = corpusFiles("/usr/share/assimp/models", {".obj"});
    RTLAB_REQUIRE_CORPUS(files);
    const SweepCounts n = sweep(files);
    RecordProperty("rendered", n.rendered);
    RecordProperty("rejected", n.rejected);
    EXPECT_GT(n.rendered, 0);
    EXPECT_GT(n.rejected, 0) << "invalid/ holds broken files";
}

// The glTF2/ folder holds glTF 2.0 files broken on purpose (wrongTypes/, IndexOutOfRange/,
// MissingBin/, ...) and files of points and lines only; PLY/ holds point clouds.
TEST(AssimpSweep, EveryGltfAndPlyRendersOrFailsWithOneClearLine) {
    std::vector<fs::path> files = corpusFiles("/usr/share/assimp/models/glTF2", {".gltf", ".glb"});
    const std::vector<fs::path> ply = corpusFiles("/usr/share/assimp/models/PLY", {".ply"});
    files.insert(files.end(), ply.begin(), ply.end());
    RTLAB_REQUIRE_CORPUS(files);
    const SweepCounts n = sweep(files);
    RecordProperty("rendered", n.rendered);
    RecordProperty("rejected", n.rejected);
    EXPECT_EQ(n.rendered + n.rejected, int(files.size()));
    EXPECT_GT(n.rendered, 0);
    EXPECT_GT(n.rejected, 0) << "the corpus holds broken files";
}

}  // namespace
}  // namespace rt
