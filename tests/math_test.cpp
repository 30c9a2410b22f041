// Unit tests of the reference's building blocks (core/reference.h) against hand-computed values:
// ray-sphere (plain and robust), ray-triangle (Moller-Trumbore and watertight), reflection,
// refraction and Fresnel (core/SHADING.md sections 2, 6 and 7).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/reference.h"

namespace {

using glm::dvec3;
using rt::ref::Ray;
namespace ref = rt::ref;

constexpr double kTol = 1e-12;

void expectVec(dvec3 actual, dvec3 expected, double tol = 1e-12) {
    EXPECT_NEAR(actual.x, expected.x, tol);
    EXPECT_NEAR(actual.y, expected.y, tol);
    EXPECT_NEAR(actual.z, expected.z, tol);
}

// --- spheres ---------------------------------------------------------------------------------

class SphereTest : public ::testing::TestWithParam<bool> {
  protected:
    std::optional<double> hit(const Ray& ray, dvec3 c, double r) const {
        return GetParam() ? ref::intersectSphereRobust(ray, c, r)
                          : ref::intersectSpherePlain(ray, c, r);
    }
};

TEST_P(SphereTest, HitFromOutsideReturnsNearSide) {
    const auto t = hit({{0, 0, -5}, {0, 0, 1}}, {0, 0, 0}, 1);
    ASSERT_TRUE(t);
    EXPECT_NEAR(*t, 4.0, kTol);
}

TEST_P(SphereTest, OffCentreHitMatchesChordGeometry) {
    // Ray at x = 0.5 through a unit sphere enters at z = -sqrt(1 - 0.25).
    const auto t = hit({{0.5, 0, -5}, {0, 0, 1}}, {0, 0, 0}, 1);
    ASSERT_TRUE(t);
    EXPECT_NEAR(*t, 5.0 - std::sqrt(0.75), kTol);
}

TEST_P(SphereTest, HitFromInsideReturnsFarSide) {
    const auto t = hit({{0, 0, 0.25}, {0, 0, 1}}, {0, 0, 0}, 2);
    ASSERT_TRUE(t);
    EXPECT_NEAR(*t, 1.75, kTol);
}

TEST_P(SphereTest, NearlyTangentRaysHitInsideAndMissOutside) {
    const double y = 1 - 1e-6;
    const auto in = hit({{0, y, -5}, {0, 0, 1}}, {0, 0, 0}, 1);
    ASSERT_TRUE(in);
    EXPECT_NEAR(*in, 5.0 - std::sqrt(1 - y * y), 1e-9);
    EXPECT_FALSE(hit({{0, 1 + 1e-6, -5}, {0, 0, 1}}, {0, 0, 0}, 1));
    EXPECT_FALSE(hit({{3, 0, -5}, {0, 0, 1}}, {0, 0, 0}, 1));
}

TEST_P(SphereTest, SphereBehindTheRayIsMissed) {
    EXPECT_FALSE(hit({{0, 0, 5}, {0, 0, 1}}, {0, 0, 0}, 1));
    EXPECT_FALSE(hit({{0, 0, 1.5}, {0, 0.6, 0.8}}, {0, 0, 0}, 1));
}

TEST_P(SphereTest, ObliqueDirectionHitsAtAnalyticDistance) {
    // Direction (0.6, 0, 0.8) from the origin toward a sphere centred 10 units along it.
    const dvec3 d(0.6, 0, 0.8);
    const auto t = hit({{0, 0, 0}, d}, 10.0 * d, 0.5);
    ASSERT_TRUE(t);
    EXPECT_NEAR(*t, 9.5, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(PlainAndRobust, SphereTest, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "Robust" : "Plain"; });

// A sphere of radius 1e-4 at distance 1e6: b^2 and 4c' are both 4e12, whose spacing in double
// (~5e-4) swallows the r^2 terms, so the plain quadratic sees a zero discriminant and cannot tell
// a hit from a miss. The robust form computes r^2 - |f|^2 directly.
TEST(SpherePrecision, RobustHandlesTinyDistantSphereThatPlainGetsWrong) {
    const dvec3 center(0, 0, 0);
    const double r = 1e-4;
    // Passes 0.5 r from the centre: analytic t = 1e6 - sqrt(r^2 - (0.5 r)^2).
    const Ray through{{0.5e-4, 0, -1e6}, {0, 0, 1}};
    const double analytic = 1e6 - std::sqrt(r * r - 0.25 * r * r);
    const auto robust = ref::intersectSphereRobust(through, center, r);
    ASSERT_TRUE(robust);
    EXPECT_NEAR(*robust, analytic, 1e-9);

    // Passes 2 r from the centre: a clear miss.
    const Ray beside{{2e-4, 0, -1e6}, {0, 0, 1}};
    EXPECT_FALSE(ref::intersectSphereRobust(beside, center, r));
    const auto plain = ref::intersectSpherePlain(beside, center, /*radius=*/r, false);
    EXPECT_TRUE(plain) << "plain quadratic no longer loses the r^2 term; pick a smaller sphere";
    // Its conservative t > 0 (core/SHADING.md section 3) sees a root it cannot trust: no hit.
    EXPECT_FALSE(ref::intersectSpherePlain(beside, center, r));
}

// --- triangles -------------------------------------------------------------------------------

const dvec3 kV0(0, 0, 0), kV1(1, 0, 0), kV2(0, 1, 0);

class TriangleTest : public ::testing::TestWithParam<bool> {
  protected:
    std::optional<ref::TriangleHit> hit(const Ray& ray, dvec3 a = kV0, dvec3 b = kV1,
                                        dvec3 c = kV2) const {
        return GetParam() ? ref::intersectTriangleWatertight(ray, a, b, c)
                          : ref::intersectTriangleMT(ray, a, b, c);
    }
};

TEST_P(TriangleTest, InteriorHitReportsDistanceAndBarycentrics) {
    for (double dz : {1.0, -1.0}) {  // both windings as seen from the ray
        const auto h = hit({{0.25, 0.125, -2 * dz}, {0, 0, dz}});
        ASSERT_TRUE(h);
        EXPECT_NEAR(h->t, 2.0, kTol);
        EXPECT_NEAR(h->u, 0.25, kTol);   // weight of v1 = (1, 0, 0)
        EXPECT_NEAR(h->v, 0.125, kTol);  // weight of v2 = (0, 1, 0)
    }
}

TEST_P(TriangleTest, ObliqueHitAtAnalyticPoint) {
    const dvec3 target(0.2, 0.3, 0), origin(1, 2, -3);
    const double len = glm::length(target - origin);
    const auto h = hit({origin, (target - origin) / len});
    ASSERT_TRUE(h);
    EXPECT_NEAR(h->t, len, 1e-12);
    EXPECT_NEAR(h->u, 0.2, 1e-12);
    EXPECT_NEAR(h->v, 0.3, 1e-12);
}

TEST_P(TriangleTest, PointsOutsideEachEdgeMiss) {
    EXPECT_FALSE(hit({{-0.01, 0.5, -1}, {0, 0, 1}}));  // beyond edge v0-v2 (x = 0)
    EXPECT_FALSE(hit({{0.5, -0.01, -1}, {0, 0, 1}}));  // beyond edge v0-v1 (y = 0)
    EXPECT_FALSE(hit({{0.51, 0.5, -1}, {0, 0, 1}}));   // beyond edge v1-v2 (x + y = 1)
    EXPECT_FALSE(hit({{0.9, 0.9, -1}, {0, 0, 1}}));    // v <= 1 but u + v > 1
}

TEST_P(TriangleTest, ParallelRayMisses) {
    EXPECT_FALSE(hit({{-1, 0.2, 0}, {1, 0, 0}}));    // in the triangle's plane
    EXPECT_FALSE(hit({{-1, 0.2, 0.5}, {1, 0, 0}}));  // above it
}

TEST_P(TriangleTest, TriangleBehindOriginMisses) { EXPECT_FALSE(hit({{0.2, 0.2, 1}, {0, 0, 1}})); }

INSTANTIATE_TEST_SUITE_P(MollerTrumboreAndWatertight, TriangleTest, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "Watertight" : "MT"; });

TEST(Triangle, MollerTrumboreAndWatertightAgreeOnInteriorPoints) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0, 1), wide(-5, 5);
    const dvec3 a(0.3, -1.2, 2.0), b(2.5, 0.4, 1.1), c(-0.7, 1.9, 3.3);
    for (int i = 0; i < 2000; ++i) {
        double u = unit(rng), v = unit(rng);
        if (u + v > 1) u = 1 - u, v = 1 - v;
        u = 0.01 + 0.98 * u, v = 0.01 + 0.98 * v;  // stay off the edges
        if (u + v > 0.99) continue;
        const dvec3 p = (1 - u - v) * a + u * b + v * c;
        const dvec3 o(wide(rng), wide(rng), wide(rng) - 10);
        const Ray ray{o, glm::normalize(p - o)};
        const auto mt = ref::intersectTriangleMT(ray, a, b, c);
        const auto wt = ref::intersectTriangleWatertight(ray, a, b, c);
        ASSERT_TRUE(mt && wt) << "sample " << i;
        EXPECT_NEAR(mt->t, glm::length(p - o), 1e-9);
        EXPECT_NEAR(mt->t, wt->t, 1e-9);
        EXPECT_NEAR(mt->u, wt->u, 1e-9);
        EXPECT_NEAR(mt->v, wt->v, 1e-9);
        EXPECT_NEAR(wt->u, u, 1e-9);
        EXPECT_NEAR(wt->v, v, 1e-9);
    }
}

// Rays aimed at points of the shared edge of two triangles must never slip between them.
TEST(Triangle, WatertightNeverMissesSharedEdge) {
    const dvec3 a(0.1, 0.2, 0.05), b(1.3, 0.1, -0.2), c(0.2, 1.7, 0.3), d(1.6, 1.4, 0.1);
    // Triangles (a, b, c) and (b, d, c) share the edge b-c.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0, 1), wide(-3, 3);
    int bothHit = 0;
    for (int i = 0; i < 20000; ++i) {
        const dvec3 p = b + unit(rng) * (c - b);
        const dvec3 o(wide(rng), wide(rng), -4 + wide(rng) * 0.5);
        const Ray ray{o, glm::normalize(p - o)};
        const bool h1 = bool(ref::intersectTriangleWatertight(ray, a, b, c));
        const bool h2 = bool(ref::intersectTriangleWatertight(ray, b, d, c));
        ASSERT_TRUE(h1 || h2) << "ray " << i << " slipped through the shared edge";
        bothHit += h1 && h2;
    }
    // Without a tie-breaking rule, rays exactly on the edge may hit both; they are rare.
    EXPECT_LT(bothHit, 20000);
}

// Rays from inside a closed octahedron must hit its surface in every direction.
TEST(Triangle, WatertightClosedMeshHasNoHoles) {
    const dvec3 v[6] = {{1.3, 0.1, 0},   {-0.9, 0.05, 0.1}, {0.1, 1.1, -0.1},
                        {0, -1.2, 0.07}, {0.03, 0.1, 1.4},  {-0.02, 0, -0.8}};
    const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                             {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    std::mt19937 rng(3);
    std::normal_distribution<double> gauss;
    for (int i = 0; i < 20000; ++i) {
        const Ray ray{{0.05, 0.02, 0.1}, glm::normalize(dvec3(gauss(rng), gauss(rng), gauss(rng)))};
        bool any = false;
        for (const auto& f : faces)
            any = any || ref::intersectTriangleWatertight(ray, v[f[0]], v[f[1]], v[f[2]]);
        ASSERT_TRUE(any) << "ray " << i << " escaped the closed mesh";
    }
    // Rays through a vertex shared by four faces.
    for (int k = 0; k < 6; ++k) {
        const Ray ray{{0.05, 0.02, 0.1}, glm::normalize(v[k] - dvec3(0.05, 0.02, 0.1))};
        bool any = false;
        for (const auto& f : faces)
            any = any || ref::intersectTriangleWatertight(ray, v[f[0]], v[f[1]], v[f[2]]);
        EXPECT_TRUE(any) << "ray through vertex " << k;
    }
}

// --- reflection, refraction, Fresnel ----------------------------------------------------------

const double kS45 = std::sqrt(0.5);  // sin 45 = cos 45

TEST(Reflect, MirrorsAboutTheNormal) {
    expectVec(ref::reflect({0.6, -0.8, 0}, {0, 1, 0}), {0.6, 0.8, 0});
    // 45-degree mirror turns a downward ray to +x.
    expectVec(ref::reflect({0, -1, 0}, {kS45, kS45, 0}), {1, 0, 0});
    // Normal incidence reverses the ray.
    expectVec(ref::reflect({0, 0, 1}, {0, 0, -1}), {0, 0, -1});
}

TEST(Refract, AirToGlassAt45Degrees) {
    // sin t = sin 45 / 1.5 = 0.47140452; cos t = sqrt(1 - 0.22222222) = 0.88191710.
    const auto t = ref::refract({kS45, -kS45, 0}, {0, 1, 0}, 1 / 1.5);
    ASSERT_TRUE(t);
    expectVec(*t, {0.4714045207910317, -0.881917103688197, 0});
    EXPECT_NEAR(glm::length(*t), 1.0, kTol);
}

TEST(Refract, GlassToAirBelowCriticalAngleBendsAway) {
    // 40 degrees inside glass (critical angle 41.81): sin t = 1.5 sin 40 = 0.96418141.
    const double s = std::sin(40 * M_PI / 180), c = std::cos(40 * M_PI / 180);
    const auto t = ref::refract({s, -c, 0}, {0, 1, 0}, 1.5);
    ASSERT_TRUE(t);
    expectVec(*t, {0.9641814145298089, -0.26524366132915767, 0});
}

TEST(Refract, NormalIncidencePassesStraightThrough) {
    const auto t = ref::refract({0, 0, 1}, {0, 0, -1}, 1 / 1.5);
    ASSERT_TRUE(t);
    expectVec(*t, {0, 0, 1});
}

TEST(Refract, GlassToAirAt45DegreesIsTotalInternalReflection) {
    // 1.5^2 * (1 - 0.5) = 1.125 > 1.
    EXPECT_FALSE(ref::refract({kS45, -kS45, 0}, {0, 1, 0}, 1.5));
    EXPECT_DOUBLE_EQ(ref::fresnel(kS45, 1.5, 1.0), 1.0);
}

TEST(Fresnel, NormalIncidenceEqualsSchlickR0) {
    const double pairs[][2] = {{1.0, 1.5}, {1.5, 1.0}, {1.0, 1.33}, {1.0, 2.42}, {1.2, 1.7}};
    for (const auto& p : pairs) {
        const double r0 = (p[0] - p[1]) / (p[0] + p[1]);
        EXPECT_NEAR(ref::fresnel(1.0, p[0], p[1]), r0 * r0, kTol) << p[0] << " -> " << p[1];
    }
    EXPECT_NEAR(ref::fresnel(1.0, 1.0, 1.5), 0.04, kTol);
    EXPECT_NEAR(ref::fresnel(1.0, 1.0, 1.33), 0.0200593121, 1e-9);
}

TEST(Fresnel, AirToGlassAt45Degrees) {
    // Rs = 0.09201330, Rp = -0.30333828 -> (Rs^2 + Rp^2) / 2.
    EXPECT_NEAR(ref::fresnel(kS45, 1.0, 1.5), 0.05023991101223594, 1e-12);
}

TEST(Fresnel, TotalInternalReflectionPastCriticalAngle) {
    const double critical = std::asin(1 / 1.5);
    EXPECT_DOUBLE_EQ(ref::fresnel(std::cos(critical + 0.01), 1.5, 1.0), 1.0);
    EXPECT_DOUBLE_EQ(ref::fresnel(0.0, 1.5, 1.0), 1.0);
    EXPECT_LT(ref::fresnel(std::cos(critical - 0.05), 1.5, 1.0), 1.0);
}

TEST(Fresnel, GrazingIncidenceApproachesOne) {
    EXPECT_GT(ref::fresnel(1e-6, 1.0, 1.5), 0.99999);
    EXPECT_NEAR(ref::fresnel(0.01, 1.0, 1.5), 0.9437525434858283, 1e-12);
    // Monotonic from normal to grazing.
    double previous = 0;
    for (double angle = 0; angle < 89.9; angle += 5) {
        const double f = ref::fresnel(std::cos(angle * M_PI / 180), 1.0, 1.5);
        EXPECT_GE(f, previous - 1e-15) << angle;
        previous = f;
    }
}

}  // namespace
