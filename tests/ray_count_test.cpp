// Every design counts the same rays (RenderOptions::countRays): per RT_RAY_* type, every
// registered device pipeline, both megakernel layouts and the queue wavefront with packets off
// and on, with its default pool and with a pool so small that paths are cut for room and traced
// again from their camera ray. Those retraced rays are the queue's extra work, reported on their
// own (extras "retraced_rays"), not rays of the image.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/scene_loader.h"
#include "megakernel/megakernel_options.h"
#include "pipelines/registry.h"
#include "test_device.h"
#include "test_scenes.h"
#include "wavefront/queue/queue.h"

namespace rt {
namespace {

int addMaterial(Scene& s, dev::Float3 ambient, dev::Float3 diffuse, dev::Float3 specular,
                float exponent, float reflectance = 0, float opacity = 1, float ior = 1) {
    dev::Material m{};
    m.ambient = ambient, m.diffuse = diffuse, m.specular = specular, m.exponent = exponent;
    m.reflectance = reflectance, m.opacity = opacity, m.ior = ior;
    s.materials.push_back(m);
    s.materialNames.push_back("m" + std::to_string(s.materials.size()));
    return int(s.materials.size()) - 1;
}

// stress/big-mesh in small: a terrain of 2 x 40^2 triangles under a transparent water plane,
// with a mirror and a glass sphere above it and two lights, seen from the same place.
Scene lake() {
    Scene s;
    s.name = "lake";
    s.environment.zenith = {0.35f, 0.55f, 0.95f};
    s.environment.horizon = {0.85f, 0.9f, 1.0f};
    s.environment.ground = {0.3f, 0.27f, 0.25f};
    const int terrain =
        addMaterial(s, {0.05f, 0.06f, 0.04f}, {0.45f, 0.55f, 0.3f}, {0.1f, 0.1f, 0.1f}, 16);
    const int water = addMaterial(s, {0, 0.01f, 0.02f}, {0.05f, 0.15f, 0.2f}, {0.9f, 0.9f, 0.9f},
                                  300, 0, 0.25f, 1.33f);
    const int mirror =
        addMaterial(s, {0, 0, 0}, {0.03f, 0.03f, 0.03f}, {0.8f, 0.8f, 0.8f}, 200, 0.9f);
    const int glass = addMaterial(s, {0, 0, 0}, {0, 0, 0}, {0.8f, 0.8f, 0.8f}, 200, 0, 0, 1.5f);
    auto height = [](float x, float z) {
        return 3 * std::sin(0.11f * x + 1.3f) * std::cos(0.09f * z + 0.4f) + 0.04f * z;
    };
    const int n = 40;
    const float size = 100, step = size / n, half = size / 2;
    auto vertex = [&](int i, int j) {
        const float x = -half + j * step, z = -half + i * step;
        return dev::Float3{x, height(x, z), z};
    };
    const dev::Float3 up{0, 1, 0};
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const dev::Float3 a = vertex(i, j), b = vertex(i, j + 1), c = vertex(i + 1, j),
                              d = vertex(i + 1, j + 1);
            s.triangles.push_back({a, c, b, up, up, up, terrain, 0});
            s.triangles.push_back({b, c, d, up, up, up, terrain, 0});
        }
    s.planes.push_back({{0, 1, 0}, 0.6f, water, {0, 0, 0}});
    s.spheres.push_back({{-8, height(-8, -10) + 5, -10}, 3, mirror, {0, 0, 0}});
    s.spheres.push_back({{-18, height(-18, -22) + 4, -22}, 2.5f, glass, {0, 0, 0}});
    dev::Light sun{}, fill{};
    sun.position = {-60, 80, -20}, sun.color = {0.95f, 0.92f, 0.85f};
    fill.position = {40, 30, -60}, fill.color = {0.25f, 0.25f, 0.3f};
    s.lights = {sun, fill};
    // From (-30, 14, -44) towards the origin.
    s.camera.position = {-30, 14, -44};
    s.camera.yaw = std::atan2(30.0f, 44.0f);
    s.camera.pitch = -std::atan2(14.0f, std::sqrt(30.0f * 30 + 44.0f * 44));
    s.camera.fovY = 55 * 3.14159265f / 180;
    finalizeScene(s);
    return s;
}

std::string typesText(const RayCounts& r) {
    return std::to_string(r[RT_RAY_PRIMARY]) + " primary, " + std::to_string(r[RT_RAY_REFLECTION]) +
           " reflection, " + std::to_string(r[RT_RAY_REFRACTION]) + " refraction, " +
           std::to_string(r[RT_RAY_SHADOW]) + " shadow";
}

// Renders `scene` with every device pipeline in every variant that traces differently and
// expects the weighted megakernel's rays, type by type. Returns the queue's paths restarted
// with the small pool.
long long expectSameCounts(const Scene& scene, const RenderOptions& base) {
    using Packets = QueuePacketMode;
    RenderOptions o = base;
    o.countRays = true;
    o.accel = RenderOptions::Accel::Wide;  // the structure the queue's packets traverse
    auto counted = [&](const std::string& pipeline, const RenderOptions& opt, Pipeline& p) {
        p.render(scene, opt);
        EXPECT_TRUE(p.stats().raysCounted) << pipeline;
        return p.stats().rays;
    };
    auto mega = makePipeline("mega", &test::device());
    setMegaLayout(o, MegaLayout::Weighted);
    const RayCounts expected = counted("mega", o, *mega);
    EXPECT_EQ(expected[RT_RAY_PRIMARY], uint64_t(o.width) * o.height * o.aa * o.aa);
    EXPECT_GT(expected[RT_RAY_SHADOW], 0u);
    if (scene.branching() == 2) EXPECT_GT(expected[RT_RAY_REFRACTION], 0u);
    long long restarted = 0;
    const bool packetsPossible = test::device().device().type == "CPU" && !scene.triangles.empty();
    for (const std::string& name : pipelineRegistry().names(true)) {
        auto p = makePipeline(name, &test::device());
        for (const PipelineVariantRun& run : pipelineRegistry().variants(true)) {
            if (run.pipeline != name) continue;
            RenderOptions v = o;
            run.apply(v);
            if (name != "queue") {
                const std::string what = run.name;  // "mega-tree"
                const RayCounts got = counted(what, v, *p);
                EXPECT_EQ(got, expected) << scene.name << ", " << what << ": " << typesText(got)
                                         << " against " << typesText(expected);
                continue;
            }
            // 512 slots: fewer than the 64 x 36 camera rays' children, so paths are cut.
            for (size_t pool : {size_t(0), size_t(512)})
                for (Packets packets : {Packets::Off, Packets::On}) {
                    if (packets == Packets::On && !packetsPossible) continue;
                    setQueuePool(v, pool);
                    setQueuePackets(v, packets);
                    const std::string what = "queue, pool " + std::to_string(pool) +
                                             (packets == Packets::On ? ", packets" : "");
                    const RayCounts got = counted(what, v, *p);
                    EXPECT_EQ(got, expected) << scene.name << ", " << what << ": " << typesText(got)
                                             << " against " << typesText(expected);
                    const nlohmann::json& extras = p->stats().extras;
                    const long long cut = extras.at("restarted_paths").get<long long>();
                    if (pool) restarted += cut;
                    // A restarted path's camera ray was traced twice: once retraced, once
                    // counted; nothing is retraced without a cut.
                    const RayCounts again = extras.at("retraced_rays").get<RayCounts>();
                    EXPECT_EQ(again[RT_RAY_PRIMARY], uint64_t(cut)) << scene.name << ", " << what;
                    if (cut == 0) EXPECT_EQ(again, RayCounts{}) << scene.name << ", " << what;
                }
        }
    }
    return restarted;
}

RenderOptions smallFrame(const Scene& scene, int bounces) {
    RenderOptions o = scene.defaults;
    o.width = 64, o.height = 36, o.bounces = bounces;
    return o;
}

// The terrain under water: most camera rays hit the water plane and spawn two children, so
// the small pool cuts paths, as the default CPU pool did for the full stress scene at 640x360.
TEST(RayCounts, EveryDesignCountsTheSameRaysOnATerrainUnderWater) {
    const Scene scene = lake();
    RenderOptions o = smallFrame(scene, 3);
    EXPECT_GT(expectSameCounts(scene, o), 0) << "the small pool cut no path";
    o.aa = 2;  // several AA samples: each pixel's paths of every sample
    EXPECT_GT(expectSameCounts(scene, o), 0) << "the small pool cut no path";
}

// The standard scenes: triangles, spheres, mirror and glass under an area light with several
// shadow samples (cornell), triangles over a plane with one child per ray (mesh, C = 1), and
// spheres alone, where the queue's packets do not apply.
TEST(RayCounts, EveryDesignCountsTheSameRaysOnTheStandardScenes) {
    for (const char* name : {"cornell", "mesh", "spheres"}) {
        SCOPED_TRACE(name);
        const Scene scene = test::load(name);
        RenderOptions o = smallFrame(scene, 3);
        o.shadowSamples = 3;
        expectSameCounts(scene, o);
    }
}

}  // namespace
}  // namespace rt
