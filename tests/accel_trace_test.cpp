// Every acceleration structure through batches of rays (bench/ray_batch.h, the pipelines' own
// Scene_Intersect and Scene_Occluded), on every standard scene, a soup of overlapping spheres and
// triangles and the stress scenes:
// - against the device's brute force (--accel none): the same primitive tests, so the same
//   closest t to the bit and the same occlusion, but where a traversal's slab test lets a
//   grazing ray through or two primitives tie;
// - against the CPU reference's double-precision traversal (core/reference.h): the same hits and
//   misses but for grazing rays, and the same t to 1e-4.
// The images of the pipelines go through one structure each (tests/accel_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "bench/ray_batch.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "test_device.h"
#include "test_scenes.h"

namespace rt {
namespace {

namespace fs = std::filesystem;
using Accel = RenderOptions::Accel;
using test::load;

constexpr Accel kStructures[] = {Accel::Bv, Accel::Grid, Accel::Bvh, Accel::Wide, Accel::Cwbvh};

struct Box {
    glm::vec3 lo{INFINITY}, hi{-INFINITY};
    void add(glm::vec3 p, float r = 0) {
        lo = glm::min(lo, p - r);
        hi = glm::max(hi, p + r);
    }
};

glm::vec3 vec(dev::Float3 f) { return {f.x, f.y, f.z}; }

// The box around the scene's spheres, triangles and camera (planes are unbounded).
Box sceneBox(const Scene& s) {
    Box b;
    b.add(vec(s.camera.position));
    for (const dev::Sphere& sp : s.spheres) b.add(vec(sp.center), sp.radius);
    for (const dev::Triangle& t : s.triangles) b.add(vec(t.v0)), b.add(vec(t.v1)), b.add(vec(t.v2));
    const glm::vec3 pad = glm::max(0.05f * (b.hi - b.lo), glm::vec3(1));
    b.lo -= pad, b.hi += pad;
    return b;
}

BatchRay batchRay(glm::vec3 from, glm::vec3 to, bool bounded) {
    const glm::vec3 d = to - from;
    const float length = glm::length(d);
    const glm::vec3 u = d / length;
    return {from.x, from.y, from.z, bounded ? length : INFINITY, u.x, u.y, u.z, 0.f};
}

// `count` rays of each kind: from the camera towards random points of the scene (coherent, as
// camera rays are), between random points inside it (incoherent, starting inside the structure's
// boxes and cells), and segments between random points (shadow rays, with a finite tMax).
std::vector<BatchRay> testRays(const Scene& s, int count) {
    const Box box = sceneBox(s);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    auto point = [&] {
        return box.lo + glm::vec3(unit(rng), unit(rng), unit(rng)) * (box.hi - box.lo);
    };
    std::vector<BatchRay> rays;
    for (int i = 0; i < count; ++i)
        rays.push_back(batchRay(vec(s.camera.position), point(), false));
    for (int i = 0; i < count; ++i) rays.push_back(batchRay(point(), point(), false));
    for (int i = 0; i < count; ++i) rays.push_back(batchRay(point(), point(), true));
    return rays;
}

struct Traced {
    std::vector<float> t;
    std::vector<int> occluded;
};

Traced trace(const Scene& scene, Accel accel, const std::vector<BatchRay>& rays) {
    RenderOptions o = scene.defaults;
    o.accel = accel;
    BatchTracer tracer(test::device(), scene, o, 0, accelName(accel));
    return {tracer.closest(rays), tracer.occluded(rays)};
}

// Rays whose answers differ, with the first few described for the failure message.
struct Differences {
    size_t count = 0;
    std::string first;
    void add(size_t i, const std::string& what) {
        if (count++ < 4) first += "\n  ray " + std::to_string(i) + ": " + what;
    }
};

// A grazing ray may slip through one traversal's slab test and not another's: one in a
// thousand may differ (none has, on PoCL), as one pixel in a thousand may in the image tests.
size_t allowed(size_t rays) { return rays / 1000; }

void expectSameAsNone(const Scene& scene, const std::vector<BatchRay>& rays, const Traced& none) {
    for (Accel accel : kStructures) {
        SCOPED_TRACE(scene.name + ", " + accelName(accel));
        const Traced got = trace(scene, accel, rays);
        Differences closest, occluded;
        for (size_t i = 0; i < rays.size(); ++i) {
            if (std::memcmp(&got.t[i], &none.t[i], sizeof(float)) != 0)
                closest.add(i, "t " + std::to_string(got.t[i]) + " against none's " +
                                   std::to_string(none.t[i]));
            if (got.occluded[i] != none.occluded[i])
                occluded.add(i, "occluded " + std::to_string(got.occluded[i]));
        }
        EXPECT_LE(closest.count, allowed(rays.size())) << "closest hits differ:" << closest.first;
        EXPECT_LE(occluded.count, allowed(rays.size())) << "occlusion differs:" << occluded.first;
    }
}

// The device's brute force against the CPU reference's traversal, in double precision.
void expectNoneMatchesReference(const Scene& scene, const std::vector<BatchRay>& rays,
                                const Traced& none) {
    SCOPED_TRACE(scene.name + ", none against the CPU reference");
    const ref::Queries host(scene, scene.defaults, false);
    Differences closest, occluded;
    size_t hits = 0, blocked = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        const BatchRay& r = rays[i];
        const ref::Ray ray{{r.ox, r.oy, r.oz}, {r.dx, r.dy, r.dz}};
        const ref::SceneHit h = host.closest(ray);
        const bool hostHit = h.kind != RT_KIND_MISS && h.t < double(r.tMax);
        const bool deviceHit = none.t[i] >= 0.f;
        hits += deviceHit;
        if (hostHit != deviceHit)
            closest.add(i, deviceHit ? "the device hits, the reference misses"
                                     : "the reference hits, the device misses");
        else if (hostHit && std::abs(none.t[i] - h.t) > 1e-4 * std::max(1.0, h.t))
            closest.add(i, "t " + std::to_string(none.t[i]) + " against " + std::to_string(h.t));
        const bool hostBlocked = std::isfinite(r.tMax) ? host.occluded(ray, r.tMax) : hostHit;
        blocked += none.occluded[i];
        if (hostBlocked != bool(none.occluded[i])) occluded.add(i, "occlusion differs");
    }
    EXPECT_LE(closest.count, allowed(rays.size())) << "closest hits differ:" << closest.first;
    EXPECT_LE(occluded.count, allowed(rays.size())) << "occlusion differs:" << occluded.first;
    // The rays must exercise both answers, or the comparison proves little.
    if (!scene.spheres.empty() || !scene.triangles.empty()) {
        EXPECT_GT(hits, rays.size() / 20);
        EXPECT_GT(blocked, rays.size() / 20);
    }
}

void expectEveryStructureMatches(const Scene& scene, int count) {
    const std::vector<BatchRay> rays = testRays(scene, count);
    const Traced none = trace(scene, Accel::None, rays);
    expectNoneMatchesReference(scene, rays, none);
    expectSameAsNone(scene, rays, none);
}

TEST(AccelTrace, StandardScenes) {
    for (const char* name : test::kScenes) expectEveryStructureMatches(load(name), 1000);
}

// Rays start in many boxes at once, and the children of a node overlap.
TEST(AccelTrace, SoupOfSpheresAndTriangles) {
    Scene scene = test::soup(300, 700, 7);
    scene.camera.position = {0, 0, -30};
    expectEveryStructureMatches(scene, 2000);
}

// The stress scenes at reduced size (4,096 spheres; a terrain of 20,000 triangles under water),
// written by scripts/make-stress.py into a folder of this test's own.
TEST(AccelTrace, SmallStressScenes) {
    const fs::path dir = fs::path(RTLAB_BIN_DIR).parent_path() / "stress-small-trace";
    const std::string cmd = "python3 scripts/make-stress.py --out " + dir.string() +
                            " --side 64 --terrain 100 > /dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    for (const char* name : {"many-spheres", "big-mesh"})
        expectEveryStructureMatches(loadScene(dir / (std::string(name) + ".json"), readImage),
                                    2000);
}

}  // namespace
}  // namespace rt
