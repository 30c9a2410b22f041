// Golden images of the standard scenes (scenes/*.json) rendered by the CPU reference at 128x96.
// They catch any change to the reference's output; an intended change is recorded by
// regenerating them with scripts/update-goldens (RTLAB_UPDATE_GOLDENS=1), then looking at them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/reference.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"

namespace {

namespace fs = std::filesystem;

// Goldens are 8-bit sRGB PNGs, so the decoded golden is off from the float render by up to half
// an sRGB code: 0.5/255 * d(linear)/d(sRGB), and that slope reaches 2.4/1.055 = 2.27 at 1.0.
// Quantisation alone thus gives at most 1.14/255 per channel, and a mean of about 0.25/255 on
// dark images and up to 0.57/255 on bright ones (the sky of empty.json measures 0.50/255).
// 2/255 per channel leaves about 0.9/255 for real differences; the mean bound of 1/255 sits
// above the quantisation floor. 0.1% of the pixels may exceed 2/255: another compiler may
// contract floating-point operations differently, which can move a pixel across a silhouette
// or flip one shadow sample. A real change to the shading moves far more pixels than that.
constexpr double kTolerance = 2.0 / 255;
constexpr double kMinFractionWithin = 0.999;
constexpr double kMaxMeanAbs = 1.0 / 255;

bool updating() {
    const char* v = std::getenv("RTLAB_UPDATE_GOLDENS");
    return v && std::string(v) == "1";
}

class GoldenTest : public ::testing::TestWithParam<std::string> {};

TEST_P(GoldenTest, ReferenceMatchesGolden) {
    const fs::path source = RTLAB_SOURCE_DIR;
    const fs::path scenePath = source / "scenes" / (GetParam() + ".json");
    const fs::path golden = source / "tests" / "golden" / (GetParam() + ".png");
    if (!fs::exists(scenePath)) GTEST_SKIP() << scenePath << " does not exist yet";

    const rt::Scene scene = rt::loadScene(scenePath, rt::readImage);
    rt::RenderOptions options = scene.defaults;  // keeps the scene's accuracy switches
    options.width = 128, options.height = 96;
    options.bounces = 3, options.shadowSamples = 4, options.aa = 1, options.adaptiveAa = false;
    const auto start = std::chrono::steady_clock::now();
    const rt::Image image = rt::renderReference(scene, options);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RecordProperty("render_seconds", std::to_string(seconds));

    if (updating()) {
        rt::writeImage(image, golden);
        GTEST_SKIP() << "wrote " << golden << " (" << seconds << " s)";
    }
    ASSERT_TRUE(fs::exists(golden))
        << golden << " is missing; run scripts/update-goldens and look at the result";
    const rt::ImageDiff diff = rt::compareImages(image, rt::readImage(golden), kTolerance);
    const bool ok = diff.fractionWithin >= kMinFractionWithin && diff.meanAbs <= kMaxMeanAbs;
    if (!ok) {
        const fs::path actual = fs::path(::testing::TempDir()) /
                                (GetParam() + "_actual_" + std::to_string(getpid()) + ".png");
        rt::writeImage(image, actual);
        ADD_FAILURE() << "render differs from " << golden << ": within " << diff.fractionWithin
                      << ", mean " << diff.meanAbs * 255 << "/255, max " << diff.maxAbs * 255
                      << "/255; actual image written to " << actual;
    }
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, GoldenTest,
                         ::testing::Values("empty", "spheres", "shadows", "cornell", "mesh",
                                           "envmap"),
                         [](const auto& info) { return info.param; });

}  // namespace
