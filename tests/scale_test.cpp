// Accuracy at every scale: every standard scene and its copies scaled by each power of
// ten from 1e-4 to 1e5 give the same image in every pipeline with the bound offset (at most 0.1%
// of pixels beyond 2/255 of the unscaled render), which the fixed epsilon does not; and a sphere
// of radius 1e-3 at distance 1e4 is shaded on the device as the double reference shades it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/pipeline.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "core/scene_scale.h"
#include "image/image_io.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_images.h"

namespace rt {
namespace {

using test::pixelsOff;

RenderOptions smallOptions(const Scene& scene) {
    RenderOptions o = scene.defaults;
    o.width = 40;
    o.height = 30;
    o.bounces = std::min(o.bounces, 3);
    o.shadowSamples = std::min(o.shadowSamples, 4);
    o.aa = 1;
    o.adaptiveAa = false;
    return o;
}

class ScaleInvariance : public ::testing::TestWithParam<std::string> {};

TEST_P(ScaleInvariance, EveryPipelineGivesTheSameImageFrom1e_4To1e5) {
    const Scene scene = loadScene("scenes/" + GetParam() + ".json", readImage);
    RenderOptions o = smallOptions(scene);
    const int limit = o.width * o.height / 1000;  // 0.1%
    // Pipelines keep a scene's device copy by its address, so every copy lives to the end.
    std::vector<Scene> scaled;
    for (int e = -4; e <= 5; ++e) scaled.push_back(scaleScene(scene, std::pow(10.0, e)));
    // Every registered pipeline, in each of its variants.
    for (const PipelineVariantRun& v : pipelineRegistry().variants()) {
        RenderOptions vo = o;
        v.apply(vo);
        std::unique_ptr<Pipeline> p = makePipeline(v.pipeline, &test::device());
        const Image base = p->render(scene, vo);
        for (int e = -4; e <= 5; ++e) {
            if (e == 0) continue;
            const int off = pixelsOff(base, p->render(scaled[e + 4], vo));
            EXPECT_LE(off, limit) << v.name << " at scale 1e" << e;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, ScaleInvariance,
                         ::testing::Values("empty", "spheres", "shadows", "cornell", "mesh",
                                           "envmap"),
                         [](const auto& info) { return info.param; });

// The test above can fail: the report's fixed epsilon breaks the glass and the shadows of a
// scene shrunk to 1e-4 (the CPU reference shows it in exact-ish arithmetic).
TEST(Scale, FixedEpsilonChangesSmallScenes) {
    const Scene scene = loadScene("scenes/spheres.json");
    RenderOptions o = smallOptions(scene);
    o.offset = RenderOptions::Offset::Fixed;
    const Image base = renderReference(scene, o);
    EXPECT_GT(pixelsOff(base, renderReference(scaleScene(scene, 1e-4), o)),
              o.width * o.height / 100);
}

// A grey Blinn-Phong sphere of radius 1e-3 at distance 1e4 straight ahead of the camera, lit
// from the camera; the image is odd-sized so that the centre pixel's ray is exactly +z. Its
// float hit point lies about one ulp (1e-3, the radius) off the sphere, so (p - c) / r was 0.977
// long and the pixel 15/255 too dark on the device.
Scene farTinySphere(float fovY) {
    Scene s;
    s.name = "far-tiny-sphere";
    dev::Material m{};
    m.ambient = {0.05f, 0.05f, 0.05f};
    m.diffuse = {0.6f, 0.5f, 0.4f};
    m.specular = {0.3f, 0.3f, 0.3f};
    m.exponent = 32.f;
    m.opacity = 1.f;
    m.ior = 1.f;
    s.materials = {m};
    s.materialNames = {"grey"};
    s.spheres.push_back({{0, 0, 1e4f}, 1e-3f, 0, {0, 0, 0}});
    s.lights.push_back({{0, 0, 0}, 0.f, {1, 1, 1}, 0.f});
    s.camera = {{0, 0, 0}, 0.f, 0.f, fovY, {0, 0}};
    finalizeScene(s);
    return s;
}

TEST(Scale, TinySphereFarAwayMatchesTheReferenceAtItsCentre) {
    const Scene scene = farTinySphere(0.5f);
    RenderOptions o;
    o.width = 41;
    o.height = 31;
    o.bounces = 1;
    const Image ref = renderReference(scene, o);
    const float* r = ref.pixel(20, 15);
    // Lit head-on: N.L = N.H = 1, so the pixel is ambient + diffuse + specular.
    EXPECT_NEAR(r[0], 0.05f + 0.6f + 0.3f, 1e-5f);
    for (const std::string& k : pipelineRegistry().names(true)) {
        const Image img = makePipeline(k, &test::device())->render(scene, o);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(img.pixel(20, 15)[c], r[c], 1.0 / 255) << k << " channel " << c;
    }
}

// Zoomed in so that the sphere covers a few hundred pixels: the device shades the disk as the
// reference does, up to the float ray's own uncertainty at 1e4 (its direction is rounded to
// 6e-8, which moves it by 6e-4 there, 60% of the radius), so the bar is on the mean.
TEST(Scale, TinySphereFarAwayIsShadedRoundNotFlat) {
    const Scene scene = farTinySphere(3e-7f);
    RenderOptions o;
    o.width = 41;
    o.height = 31;
    o.bounces = 1;
    const Image ref = renderReference(scene, o);
    for (const std::string& k : pipelineRegistry().names(true)) {
        const Image img = makePipeline(k, &test::device())->render(scene, o);
        double sum = 0;
        int disk = 0;
        for (size_t i = 0; i < img.rgb.size(); i += 3) {
            // The sky's blue is 1 here; the sphere's at most 0.75.
            if (ref.rgb[i + 2] > 0.95f && img.rgb[i + 2] > 0.95f) continue;
            ++disk;
            sum += std::abs(double(img.rgb[i]) - ref.rgb[i]);
        }
        ::testing::Test::RecordProperty(std::string("disk_pixels_") + k, disk);
        ASSERT_GT(disk, 100) << k;
        EXPECT_LT(sum / disk, 0.05) << k << ": mean error on the disk";
    }
}

}  // namespace
}  // namespace rt
