// The CPU reference's BVHs (core/reference_bvh.h) against brute force: the same closest hit
// (t, kind, object and barycentrics, to the bit) and the same any-hit answer for batches of
// rays through scenes built to tie, and bit-identical images of many-sphere scenes with
// mirrors, glass, soft shadows and a ground plane.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "core/reference.h"

namespace {

using rt::Image;
using rt::RenderOptions;
using rt::Scene;
using rt::dev::Float3;
using rt::ref::Queries;
using rt::ref::Ray;
using rt::ref::SceneHit;

int addMaterial(Scene& s, Float3 diffuse, float reflectance = 0, float opacity = 1) {
    rt::dev::Material m{};
    m.ambient = {0.05f, 0.05f, 0.05f}, m.diffuse = diffuse, m.specular = {0.5f, 0.5f, 0.5f};
    m.exponent = 40, m.reflectance = reflectance, m.opacity = opacity, m.ior = 1.5f;
    s.materials.push_back(m);
    s.materialNames.push_back("m" + std::to_string(s.materials.size()));
    return int(s.materials.size()) - 1;
}

void addSphere(Scene& s, Float3 c, float r, int material) {
    rt::dev::Sphere sp{};
    sp.center = c, sp.radius = r, sp.material = material;
    s.spheres.push_back(sp);
}

void addPlane(Scene& s, Float3 n, float offset, int material) {
    rt::dev::Plane p{};
    p.normal = n, p.offset = offset, p.material = material;
    s.planes.push_back(p);
}

void addTriangle(Scene& s, Float3 a, Float3 b, Float3 c, int material) {
    rt::dev::Triangle t{};
    t.v0 = a, t.v1 = b, t.v2 = c;
    const Float3 up{0, 1, 0};
    t.n0 = up, t.n1 = up, t.n2 = up, t.material = material;
    s.triangles.push_back(t);
}

void addLight(Scene& s, Float3 p, Float3 color, float radius = 0) {
    rt::dev::Light l{};
    l.position = p, l.color = color, l.radius = radius;
    s.lights.push_back(l);
}

Scene baseScene() {
    Scene s;
    s.name = "reference-bvh";
    s.environment.zenith = {0.35f, 0.55f, 0.95f};
    s.environment.horizon = {0.85f, 0.9f, 1.0f};
    s.environment.ground = {0.3f, 0.27f, 0.25f};
    return s;
}

// An adversary for the tie rule: 3,000 random overlapping spheres in [-6, 6]^3, every fifth one
// an exact copy of an earlier one (so two objects give the same t), some of them resting on
// the plane y = -6 (a sphere and the plane meet at one t), plus triangles lying in that plane
// (a plane and a triangle at the same t), a copy of each (triangle ties) and a tilted fan.
Scene tieScene() {
    Scene s = baseScene();
    const int m = addMaterial(s, {0.6f, 0.5f, 0.4f});
    std::mt19937 rng(30);
    std::uniform_real_distribution<float> pos(-6, 6), rad(0.05f, 1.2f);
    for (int i = 0; i < 3000; ++i) {
        if (i % 5 == 4) {
            s.spheres.push_back(s.spheres[rng() % s.spheres.size()]);
            continue;
        }
        const float r = rad(rng);
        const float y = i % 7 == 0 ? -6 + r : pos(rng);  // every seventh on the plane
        addSphere(s, {pos(rng), y, pos(rng)}, r, m);
    }
    addPlane(s, {0, 1, 0}, -6, m);
    addPlane(s, {0.6f, 0, 0.8f}, 9, m);
    for (int i = 0; i < 200; ++i) {
        const float x = pos(rng), z = pos(rng);
        addTriangle(s, {x, -6, z}, {x, -6, z + 1}, {x + 1, -6, z}, m);  // in the plane
        const Float3 a{pos(rng), pos(rng), pos(rng)};
        const Float3 b{a.x + 1, a.y + pos(rng) / 6, a.z}, c{a.x, a.y + 1, a.z + pos(rng) / 6};
        addTriangle(s, a, b, c, m);
        if (i % 4 == 0) s.triangles.push_back(s.triangles[rng() % s.triangles.size()]);
    }
    return s;
}

Float3 randomDir(std::mt19937& rng) {
    std::normal_distribution<float> g;
    return {g(rng), g(rng), g(rng)};
}

Ray makeRay(Float3 o, Float3 d) {
    const glm::dvec3 dir(d.x, d.y, d.z);
    return Ray{glm::dvec3(o.x, o.y, o.z), glm::normalize(dir)};
}

// Rays from inside the cloud (origins inside spheres), from its surface, from far away aimed
// at random spheres (grazing hits at a distance, where the sphere routines round the most),
// and along the axes (zero direction components in the slab test).
std::vector<Ray> rayBatch(const Scene& s, int count) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> pos(-7, 7), unit(-1, 1);
    std::vector<Ray> rays;
    for (int i = 0; i < count; ++i) {
        const rt::dev::Sphere& target = s.spheres[rng() % s.spheres.size()];
        switch (i % 4) {
            case 0:
                rays.push_back(makeRay({pos(rng), pos(rng), pos(rng)}, randomDir(rng)));
                break;
            case 1: {  // from a sphere's centre, or just off its surface
                const Float3 d = randomDir(rng);
                const glm::dvec3 n = glm::normalize(glm::dvec3(d.x, d.y, d.z));
                const double r = target.radius * (i % 8 == 1 ? 0.0 : 1.0 + 1e-6);
                const glm::dvec3 c(target.center.x, target.center.y, target.center.z);
                rays.push_back(makeRay({0, 0, 0}, randomDir(rng)));
                rays.back().origin = c + r * n;
                break;
            }
            case 2: {  // from far away at a point on the target's rim
                const Float3 d = randomDir(rng);
                const double far = i % 8 == 2 ? 1e4 : 200.0;
                const glm::dvec3 o = far * glm::normalize(glm::dvec3(d.x, d.y, d.z));
                const glm::dvec3 c(target.center.x, target.center.y, target.center.z);
                const glm::dvec3 w = glm::normalize(c - o);
                const glm::dvec3 side = glm::normalize(glm::cross(w, glm::dvec3(0.3, 1, 0.1)));
                const double edge = target.radius * (1 + 1e-7 * unit(rng));
                rays.push_back(Ray{o, glm::normalize(c + edge * side - o)});
                break;
            }
            default: {
                glm::dvec3 d(0);
                d[i / 4 % 3] = (i / 12) % 2 ? 1 : -1;
                rays.push_back(Ray{glm::dvec3(pos(rng), pos(rng), pos(rng)), d});
            }
        }
    }
    return rays;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expectSameHits(const Scene& s, const RenderOptions& o, const std::vector<Ray>& rays,
                    int* ties) {
    const Queries fast(s, o, false), brute(s, o, true);
    int hits = 0, kinds[4] = {};
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const SceneHit a = fast.closest(rays[i]), b = brute.closest(rays[i]);
        ASSERT_EQ(a.kind, b.kind) << "ray " << i;
        ASSERT_EQ(a.object, b.object) << "ray " << i;
        ASSERT_TRUE(sameBits(a.t, b.t) && sameBits(a.u, b.u) && sameBits(a.v, b.v))
            << "ray " << i << ": t " << a.t << " against " << b.t;
        if (b.kind == RT_KIND_MISS) continue;
        ++hits, ++kinds[b.kind];
        // Shadow rays that end just before, at and just past the hit, and far beyond it.
        for (double length : {b.t * (1 - 1e-12), b.t, b.t * (1 + 1e-12), b.t * 3})
            ASSERT_EQ(fast.occluded(rays[i], length), brute.occluded(rays[i], length))
                << "ray " << i << ", length " << length;
    }
    // The batch exercised every kind of object.
    EXPECT_GT(hits, int(rays.size()) / 2);
    EXPECT_GT(kinds[RT_KIND_SPHERE], 0);
    EXPECT_GT(kinds[RT_KIND_PLANE], 0);
    EXPECT_GT(kinds[RT_KIND_TRIANGLE], 0);
    if (ties) {
        // A tie that went to the later object would have shown above; count the rays that
        // found two objects at their closest t, so that the test knows it met some.
        *ties = 0;
        for (const Ray& r : rays) {
            const SceneHit b = brute.closest(r);
            if (b.kind != RT_KIND_SPHERE) continue;
            const rt::dev::Sphere& hit = s.spheres[b.object];
            for (std::size_t j = b.object + 1; j < s.spheres.size(); ++j)
                if (std::memcmp(&s.spheres[j], &hit, sizeof hit) == 0) {
                    ++*ties;
                    break;
                }
        }
    }
}

// Rays from 1e2 to 1e6 away that graze a sphere of a sparse field, along an axis (a zero
// direction component in the slab test) or not, at distances from the rim where the plain
// routine's rounding turns a near miss into a hit: boxes padded by their own size alone would
// cull those spheres.
TEST(ReferenceBvh, SameHitsAsBruteForceForDistantGrazingRays) {
    Scene s = baseScene();
    const int m = addMaterial(s, {0.6f, 0.5f, 0.4f});
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> pos(-100, 100), rad(0.01f, 2), unit(-1, 1);
    for (int i = 0; i < 500; ++i) addSphere(s, {pos(rng), pos(rng), pos(rng)}, rad(rng), m);
    std::vector<Ray> rays;
    std::vector<int> targets;
    for (int i = 0; i < 6000; ++i) {
        const int target = int(rng() % s.spheres.size());
        const rt::dev::Sphere& sp = s.spheres[target];
        const glm::dvec3 c(sp.center.x, sp.center.y, sp.center.z);
        const double far = std::pow(10.0, 2 + i % 5), r = sp.radius;
        // The plain routine's false hits reach about 1e-16 (far / r)^2 of the radius past it.
        const double off = r * (1 + std::min(0.1, 4e-16 * (far / r) * (far / r)) * unit(rng));
        if (i % 2) {
            const int along = i / 2 % 3, across = (along + 1 + i / 6 % 2) % 3;
            glm::dvec3 o = c, d(0);
            o[across] += off;
            o[along] -= far;
            d[along] = 1;
            rays.push_back(Ray{o, d});
        } else {
            const Ray random = makeRay({0, 0, 0}, randomDir(rng));
            const glm::dvec3 o = c - far * random.dir;
            const glm::dvec3 side = glm::normalize(glm::cross(random.dir, glm::dvec3(0.3, 1, 0.1)));
            rays.push_back(Ray{o, glm::normalize(c + off * side - o)});
        }
        targets.push_back(target);
    }
    for (bool robust : {false, true}) {
        SCOPED_TRACE(robust ? "robust spheres" : "plain spheres");
        RenderOptions o;
        o.robustSphere = robust;
        const Queries fast(s, o, false), brute(s, o, true);
        int grazed = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const SceneHit a = fast.closest(rays[i]), b = brute.closest(rays[i]);
            ASSERT_EQ(a.object, b.object) << "ray " << i;
            ASSERT_TRUE(sameBits(a.t, b.t)) << "ray " << i;
            grazed += b.object == targets[i];
            if (b.kind == RT_KIND_MISS) continue;
            for (double length : {b.t, b.t * 2})
                ASSERT_EQ(fast.occluded(rays[i], length), brute.occluded(rays[i], length))
                    << "ray " << i;
        }
        EXPECT_GT(grazed, 1000);  // about half the rays pass inside the rim
    }
}

TEST(ReferenceBvh, SameClosestAndAnyHitsAsBruteForceWithTies) {
    const Scene s = tieScene();
    const std::vector<Ray> rays = rayBatch(s, 4000);
    for (bool robust : {false, true})
        for (bool watertight : {false, true}) {
            SCOPED_TRACE(std::string(robust ? "robust" : "plain") + " spheres, " +
                         (watertight ? "watertight" : "Moller-Trumbore") + " triangles");
            RenderOptions o;
            o.robustSphere = robust, o.watertight = watertight;
            int ties = 0;
            expectSameHits(s, o, rays, &ties);
            EXPECT_GT(ties, 300) << ties;  // closest hits on a sphere with a later exact copy
        }
}

// A field of small spheres on a ground plane (like stress/many-spheres), with mirror, glass and
// gold spheres, a large mirror and a large glass sphere, two lights (one of them soft).
Scene sphereField(int side) {
    Scene s = baseScene();
    const int ground = addMaterial(s, {0.55f, 0.55f, 0.5f});
    const int kinds[] = {addMaterial(s, {0.75f, 0.18f, 0.12f}), addMaterial(s, {0.2f, 0.65f, 0.2f}),
                         addMaterial(s, {0.7f, 0.55f, 0.2f}, 0.3f),
                         addMaterial(s, {0.03f, 0.03f, 0.03f}, 0.9f),
                         addMaterial(s, {0, 0, 0}, 0, 0)};
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> rad(0.15f, 0.6f), jitter(-0.05f, 0.05f);
    const float half = (side - 1) / 2.0f;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const float r = rad(rng);  // up to 0.6: neighbours overlap
            addSphere(s, {-half + i + jitter(rng), r, -half + j + jitter(rng)}, r,
                      kinds[rng() % 5]);
        }
    addSphere(s, {-2.2f, 1.6f, -half - 3}, 1.6f, kinds[3]);
    addSphere(s, {2.2f, 1.6f, -half - 3}, 1.6f, kinds[4]);
    addPlane(s, {0, 1, 0}, 0, ground);
    addLight(s, {-half * 0.6f, 40, -half * 0.8f}, {0.9f, 0.88f, 0.8f}, 2.0f);
    addLight(s, {half, 25, 0}, {0.3f, 0.3f, 0.4f});
    s.camera.position = {0, 6, -half - 12};
    s.camera.pitch = -0.35f;
    s.camera.fovY = 0.9f;
    return s;
}

bool sameImage(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

TEST(ReferenceBvh, ManySphereImagesBitIdenticalToBruteForce) {
    const Scene s = sphereField(48);  // 2,306 spheres
    RenderOptions o;
    o.width = 96, o.height = 54, o.bounces = 3, o.aa = 1, o.shadowSamples = 2;
    for (bool robust : {false, true})
        for (RenderOptions::Offset offset :
             {RenderOptions::Offset::Bound, RenderOptions::Offset::Fixed}) {
            SCOPED_TRACE(std::string(robust ? "robust" : "plain") + " spheres, offset " +
                         std::to_string(int(offset)));
            o.robustSphere = robust, o.offset = offset;
            const Image fast = rt::renderReference(s, o),
                        brute = rt::renderReferenceBruteForce(s, o);
            EXPECT_TRUE(sameImage(fast, brute));
            // Not a blank frame: the field, the plane and the sky all show.
            double lo = 1e9, hi = -1e9;
            for (float v : fast.rgb) lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
            EXPECT_LT(lo, 0.1);
            EXPECT_GT(hi, 0.5);
        }
}

// The same with the tie scene seen from outside: secondary rays start on surfaces that touch
// or cut through one another.
TEST(ReferenceBvh, TieSceneImageBitIdenticalToBruteForce) {
    Scene s = tieScene();
    s.materials[0].reflectance = 0.5f;
    addLight(s, {10, 20, -15}, {0.8f, 0.8f, 0.8f});
    s.camera.position = {0, 0, -20};
    s.camera.fovY = 0.8f;
    RenderOptions o;
    o.width = 64, o.height = 48, o.bounces = 2, o.aa = 1, o.shadowSamples = 1;
    EXPECT_TRUE(sameImage(rt::renderReference(s, o), rt::renderReferenceBruteForce(s, o)));
}

}  // namespace
