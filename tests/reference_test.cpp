// Small renders of hand-built scenes through the CPU reference (core/reference.cpp), checked
// against values computed by hand from core/SHADING.md: camera, sky, Blinn-Phong, shadows,
// mirror and glass combining, cubemap orientation, anti-aliasing and threading.
#include "core/reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace {

using rt::Image;
using rt::RenderOptions;
using rt::Scene;
using rt::dev::Float3;

constexpr float kPi = 3.14159265358979f;

Scene emptyScene() {
    Scene s;
    s.name = "test";
    s.camera.position = {0, 0, 0};
    s.camera.fovY = kPi / 2;  // D = 1
    s.environment.zenith = {0.35f, 0.55f, 0.95f};
    s.environment.horizon = {0.85f, 0.9f, 1.0f};
    s.environment.ground = {0.3f, 0.27f, 0.25f};
    return s;
}

// An odd size puts the centre pixel's ray exactly on the camera axis.
RenderOptions options(int w = 33, int h = 25, int bounces = 0) {
    RenderOptions o;
    o.width = w, o.height = h, o.bounces = bounces, o.aa = 1, o.shadowSamples = 1;
    return o;
}

int addMaterial(Scene& s, Float3 ambient, Float3 diffuse = {}, Float3 specular = {},
                float exponent = 1, float reflectance = 0, float opacity = 1, float ior = 1) {
    rt::dev::Material m{};
    m.ambient = ambient, m.diffuse = diffuse, m.specular = specular, m.exponent = exponent;
    m.reflectance = reflectance, m.opacity = opacity, m.ior = ior;
    s.materials.push_back(m);
    s.materialNames.push_back("m" + std::to_string(s.materials.size()));
    return int(s.materials.size()) - 1;
}

void addSphere(Scene& s, Float3 c, float r, int material) {
    rt::dev::Sphere sp{};
    sp.center = c, sp.radius = r, sp.material = material;
    s.spheres.push_back(sp);
}

void addLight(Scene& s, Float3 p, Float3 color = {1, 1, 1}, float radius = 0) {
    rt::dev::Light l{};
    l.position = p, l.color = color, l.radius = radius;
    s.lights.push_back(l);
}

void expectPixel(const Image& img, int x, int y, double r, double g, double b, double tol = 1e-6) {
    const float* p = img.pixel(x, y);
    EXPECT_NEAR(p[0], r, tol) << "pixel " << x << "," << y;
    EXPECT_NEAR(p[1], g, tol) << "pixel " << x << "," << y;
    EXPECT_NEAR(p[2], b, tol) << "pixel " << x << "," << y;
}

bool same(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

TEST(Reference, EmptySceneIsTheSkyGradient) {
    const Image img = rt::renderReference(emptyScene(), options(32, 24));
    ASSERT_EQ(img.width, 32);
    ASSERT_EQ(img.height, 24);
    // Pixel (0,0): Nc = (-31/32 * 4/3, 23/24, 1), d.y = 0.50601417 -> horizon + (zenith-horizon) y.
    expectPixel(img, 0, 0, 0.5969929, 0.7228950, 0.9746993);
    // Pixel (10,5): d.y = 0.44175800.
    expectPixel(img, 10, 5, 0.6291210, 0.7453847, 0.9779121);
    // Pixel (31,23): d.y = -0.50601417 -> horizon + (ground-horizon)(-y).
    expectPixel(img, 31, 23, 0.5716922, 0.5812111, 0.6204894);
}

TEST(Reference, DiffuseSphereCentreIsBlinnPhong) {
    Scene s = emptyScene();
    addSphere(s, {0, 0, 5}, 1,
              addMaterial(s, {0.1f, 0.1f, 0.1f}, {0.5f, 0.25f, 0.125f}, {0.2f, 0.2f, 0.2f}, 10));
    addLight(s, {3, 0, 0});
    const Image img = rt::renderReference(s, options());
    // p = (0,0,4), N = (0,0,-1), L = (0.6,0,-0.8): N.L = 0.8; H = normalize(0.6,0,-1.8),
    // N.H = 0.9486833, N.H^10 = 0.9^5 = 0.59049. colour = A + D*0.8 + S*0.59049.
    expectPixel(img, 16, 12, 0.1 + 0.4 + 0.2 * 0.59049, 0.1 + 0.2 + 0.2 * 0.59049,
                0.1 + 0.1 + 0.2 * 0.59049);
    // A light behind the surface (N.L <= 0) adds nothing.
    addLight(s, {0, 0, 10}, {5, 5, 5});
    expectPixel(rt::renderReference(s, options()), 16, 12, 0.1 + 0.4 + 0.2 * 0.59049,
                0.1 + 0.2 + 0.2 * 0.59049, 0.1 + 0.1 + 0.2 * 0.59049);
}

// A wall at z = 10 lit from (0,3,0), and a ball at (0,1.5,5) on the shadow ray of the centre
// pixel but off the camera ray.
Scene shadowScene(float lightRadius) {
    Scene s = emptyScene();
    const int wall = addMaterial(s, {0.05f, 0.05f, 0.05f}, {0.8f, 0.8f, 0.8f});
    rt::dev::Plane pl{};
    pl.normal = {0, 0, -1}, pl.offset = -10, pl.material = wall;
    s.planes.push_back(pl);
    addSphere(s, {0, 1.5f, 5}, lightRadius > 0 ? 0.2f : 0.5f, addMaterial(s, {1, 0, 0}));
    addLight(s, {0, 3, 0}, {1, 1, 1}, lightRadius);
    return s;
}

TEST(Reference, HardShadowDarkensByShadowStrength) {
    Scene s = shadowScene(0);
    const double lit = 0.05 + 0.8 * 10 / std::sqrt(109.0);  // N.L = 10 / sqrt(109)
    Scene unblocked = s;
    unblocked.spheres.clear();
    expectPixel(rt::renderReference(unblocked, options()), 16, 12, lit, lit, lit);

    RenderOptions o = options();
    o.shadowStrength = 1;
    expectPixel(rt::renderReference(s, o), 16, 12, 0.05, 0.05, 0.05);
    o.shadowStrength = 0.7f;
    const double partial = 0.05 + (1 - 0.7) * (lit - 0.05);
    expectPixel(rt::renderReference(s, o), 16, 12, partial, partial, partial);
    o.shadowStrength = 0;
    expectPixel(rt::renderReference(s, o), 16, 12, lit, lit, lit);
}

TEST(Reference, SoftShadowVisibilityIsAFractionOfSamples) {
    Scene s = shadowScene(1.0f);
    RenderOptions o = options();
    o.shadowSamples = 16;
    const double lit = 0.05 + 0.8 * 10 / std::sqrt(109.0);
    const double value = rt::renderReference(s, o).pixel(16, 12)[0];
    const double visible = (value - 0.05) / (lit - 0.05) * 16;  // 16 - H
    EXPECT_NEAR(visible, std::round(visible), 1e-4);
    EXPECT_GT(std::round(visible), 0) << "penumbra expected, got umbra";
    EXPECT_LT(std::round(visible), 16) << "penumbra expected, got full light";
}

TEST(Reference, MirrorNeedsABounce) {
    Scene s = emptyScene();
    addSphere(s, {0, 0, 5}, 1, addMaterial(s, {0.1f, 0.2f, 0.3f}, {}, {}, 1, 0.8f));
    const Image b0 = rt::renderReference(s, options(33, 25, 0));
    const Image b1 = rt::renderReference(s, options(33, 25, 1));
    expectPixel(b0, 16, 12, 0.1, 0.2, 0.3);
    // The reflected ray (0,0,-1) sees the horizon: 0.2 A + 0.8 horizon.
    expectPixel(b1, 16, 12, 0.2 * 0.1 + 0.8 * 0.85, 0.2 * 0.2 + 0.8 * 0.9, 0.2 * 0.3 + 0.8 * 1.0);
    // Sky pixels do not depend on the bounce limit.
    expectPixel(b1, 0, 0, b0.pixel(0, 0)[0], b0.pixel(0, 0)[1], b0.pixel(0, 0)[2], 0);
}

TEST(Reference, GlassSphereCentreCombinesFresnelAndOpacity) {
    Scene s = emptyScene();
    const double a[3] = {0.1, 0.2, 0.3}, hor[3] = {0.85, 0.9, 1.0};
    const double o = 0.25, f = 0.04;  // ((1 - 1.5) / (1 + 1.5))^2 at normal incidence
    addSphere(s, {0, 0, 5}, 1, addMaterial(s, {0.1f, 0.2f, 0.3f}, {}, {}, 1, 0, 0.25f, 1.5f));
    const Image img = rt::renderReference(s, options(33, 25, 2));
    // Depth 1 (back wall, inside): reflection = A (depth 2 hits the front wall), refraction =
    // horizon. Depth 0: reflection = horizon, refraction = depth 1.
    double expected[3];
    for (int c = 0; c < 3; ++c) {
        const double inner = (1 - f) * (o * a[c] + (1 - o) * hor[c]) + f * a[c];
        expected[c] = (1 - f) * (o * a[c] + (1 - o) * inner) + f * hor[c];
    }
    expectPixel(img, 16, 12, expected[0], expected[1], expected[2]);
}

TEST(Reference, BackFacingTriangleIsShadedFromTheVisibleSide) {
    Scene s = emptyScene();
    const int m = addMaterial(s, {0.1f, 0.1f, 0.1f}, {0.3f, 0.4f, 0.5f}, {0.25f, 0.25f, 0.25f}, 8);
    rt::dev::Triangle t{};
    // Winding and vertex normals face +z, away from the camera.
    t.v0 = {-3, -3, 5}, t.v1 = {3, -3, 5}, t.v2 = {0, 3, 5};
    t.n0 = t.n1 = t.n2 = {0, 0, 1};
    t.material = m;
    s.triangles.push_back(t);
    addLight(s, {0, 0, 0});
    // Flipped normal (0,0,-1), L = H = (0,0,-1): A + D + S.
    for (bool watertight : {true, false}) {
        RenderOptions o = options();
        o.watertight = watertight;
        expectPixel(rt::renderReference(s, o), 16, 12, 0.65, 0.75, 0.85);
    }
}

TEST(Reference, CameraYawTurnsTowardPlusXAndPitchLooksUp) {
    Scene s = emptyScene();
    addSphere(s, {5, 0, 0}, 1, addMaterial(s, {1, 0, 0}));
    addSphere(s, {0, 5, 0}, 1, addMaterial(s, {0, 1, 0}));
    s.camera.yaw = kPi / 2;
    expectPixel(rt::renderReference(s, options()), 16, 12, 1, 0, 0);
    s.camera.yaw = 0, s.camera.pitch = kPi / 2;
    expectPixel(rt::renderReference(s, options()), 16, 12, 0, 1, 0);
}

TEST(Reference, RowZeroIsTheTopAndXGrowsToTheRight) {
    Scene s = emptyScene();
    addSphere(s, {0, 1.5f, 5}, 0.5f, addMaterial(s, {1, 0, 0}));
    addSphere(s, {1.5f, 0, 5}, 0.5f, addMaterial(s, {0, 1, 0}));
    const Image img = rt::renderReference(s, options());
    expectPixel(img, 16, 8, 1, 0, 0);       // Nc.y = 1 - 17/25 = 0.32
    expectPixel(img, 20, 12, 0, 1, 0);      // Nc.x = (41/33 - 1) * 33/25 = 0.32
    EXPECT_GT(img.pixel(16, 16)[2], 0.5f);  // mirrored positions show the sky
    EXPECT_GT(img.pixel(12, 12)[2], 0.5f);
}

// A 2x2 image at 90 degrees looks at the four texel centres of one face, so the image must
// reproduce the face as stored (row 0 on top) for all six view directions.
TEST(Reference, CubemapFacesAppearAsStored) {
    Scene s = emptyScene();
    s.environment.cubemapSize = 2;
    for (int face = 0; face < 6; ++face)
        for (int texel = 0; texel < 4; ++texel)
            for (int c = 0; c < 3; ++c)
                s.environment.cubemap.push_back(0.1f * face + 0.02f * texel + 0.3f * c);
    const float views[6][2] = {{kPi / 2, 0},  {-kPi / 2, 0}, {0, kPi / 2},
                               {0, -kPi / 2}, {0, 0},        {kPi, 0}};  // yaw, pitch
    for (int face = 0; face < 6; ++face) {
        s.camera.yaw = views[face][0], s.camera.pitch = views[face][1];
        const Image img = rt::renderReference(s, options(2, 2));
        for (int texel = 0; texel < 4; ++texel) {
            const double v = 0.1 * face + 0.02 * texel;
            SCOPED_TRACE("face " + std::to_string(face) + " texel " + std::to_string(texel));
            expectPixel(img, texel % 2, texel / 2, v, v + 0.3, v + 0.6, 1e-5);
        }
    }
}

TEST(Reference, SupersamplingAConstantImageChangesNothing) {
    Scene s = emptyScene();
    s.environment.zenith = s.environment.horizon = s.environment.ground = {0.2f, 0.4f, 0.6f};
    addSphere(s, {0, 0, 0}, 50, addMaterial(s, {0.3f, 0.5f, 0.7f}));  // camera inside
    const Image aa1 = rt::renderReference(s, options(32, 24));
    RenderOptions o = options(32, 24);
    o.aa = 2;
    const Image aa2 = rt::renderReference(s, o);
    EXPECT_TRUE(same(aa1, aa2));
    expectPixel(aa2, 7, 9, 0.3, 0.5, 0.7);
}

// A busy scene: every primitive, glass, mirror, a soft light and a hard one.
Scene busyScene() {
    Scene s = emptyScene();
    s.camera.position = {0, 1, -4};
    s.camera.pitch = -0.2f;
    s.camera.fovY = 1.0f;
    const int matte =
        addMaterial(s, {0.05f, 0.05f, 0.05f}, {0.7f, 0.6f, 0.5f}, {0.3f, 0.3f, 0.3f}, 20);
    const int mirror = addMaterial(s, {0, 0, 0}, {0.1f, 0.1f, 0.1f}, {0.5f, 0.5f, 0.5f}, 50, 0.8f);
    const int glass = addMaterial(s, {0, 0, 0}, {0, 0, 0}, {0.8f, 0.8f, 0.8f}, 80, 0, 0.1f, 1.5f);
    addSphere(s, {-1.2f, 0, 1}, 1, mirror);
    addSphere(s, {1.2f, 0, 0.5f}, 1, glass);
    addSphere(s, {0, -0.4f, -1}, 0.6f, matte);
    rt::dev::Plane floor{};
    floor.normal = {0, 1, 0}, floor.offset = -1, floor.material = matte;
    s.planes.push_back(floor);
    rt::dev::Triangle t{};
    t.v0 = {-3, -1, 3}, t.v1 = {0, 2.5f, 3.5f}, t.v2 = {3, -1, 3};  // faces the camera
    t.n0 = {0, 0, -1}, t.n1 = {-0.3f, 0.2f, -0.93f}, t.n2 = {0.3f, 0, -0.95f};
    t.material = matte;
    s.triangles.push_back(t);
    addLight(s, {2, 4, -2}, {0.8f, 0.8f, 0.8f}, 0.5f);
    addLight(s, {-3, 3, -1}, {0.4f, 0.4f, 0.5f});
    return s;
}

TEST(Reference, ThreadCountDoesNotChangeABit) {
    const Scene s = busyScene();
    RenderOptions o = options(37, 23, 3);
    o.shadowSamples = 5;
    o.aa = 2;
    const Image one = rt::renderReference(s, o, 1);
    EXPECT_TRUE(same(one, rt::renderReference(s, o, 0)));
    EXPECT_TRUE(same(one, rt::renderReference(s, o, 3)));
    o.adaptiveAa = true, o.aa = 3;
    EXPECT_TRUE(same(rt::renderReference(s, o, 1), rt::renderReference(s, o, 4)));
}

// Sub-pixel (sx, sy) of pixel x at aa 2 is the pixel centre 2x + sx of a 2x larger image. Point
// lights only: soft-shadow samples are keyed by pixel and AA sample (core/sampling.h), which
// differ between the two images.
TEST(Reference, Aa2AveragesTheFourSubpixelRays) {
    Scene s = busyScene();
    for (rt::dev::Light& light : s.lights) light.radius = 0;
    RenderOptions o = options(20, 15, 2);
    o.aa = 2;
    const Image aa2 = rt::renderReference(s, o);
    const Image big = rt::renderReference(s, options(40, 30, 2));
    double maxDiff = 0;
    for (int y = 0; y < 15; ++y)
        for (int x = 0; x < 20; ++x)
            for (int c = 0; c < 3; ++c) {
                const double mean =
                    (double(big.pixel(2 * x, 2 * y)[c]) + big.pixel(2 * x + 1, 2 * y)[c] +
                     big.pixel(2 * x, 2 * y + 1)[c] + big.pixel(2 * x + 1, 2 * y + 1)[c]) /
                    4;
                maxDiff = std::max(maxDiff, std::abs(mean - aa2.pixel(x, y)[c]));
            }
    EXPECT_LT(maxDiff, 1e-6);
}

TEST(Reference, AdaptiveAaSupersamplesExactlyTheEdgePixels) {
    const Scene s = busyScene();
    RenderOptions o = options(40, 30, 2);
    const Image centre = rt::renderReference(s, o);
    o.aa = 3;
    const Image full = rt::renderReference(s, o);
    o.adaptiveAa = true;
    const Image adaptive = rt::renderReference(s, o);
    auto differs = [&](int x, int y, int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= 40 || ny >= 30) return false;
        for (int c = 0; c < 3; ++c)
            if (std::abs(centre.pixel(x, y)[c] - centre.pixel(nx, ny)[c]) > 0.1f) return true;
        return false;
    };
    int edges = 0;
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x) {
            const bool edge = differs(x, y, x - 1, y) || differs(x, y, x + 1, y) ||
                              differs(x, y, x, y - 1) || differs(x, y, x, y + 1);
            edges += edge;
            const Image& expected = edge ? full : centre;
            for (int c = 0; c < 3; ++c)
                ASSERT_EQ(adaptive.pixel(x, y)[c], expected.pixel(x, y)[c])
                    << x << "," << y << " edge=" << edge;
        }
    EXPECT_GT(edges, 20);
    EXPECT_LT(edges, 40 * 30 / 2);
}

// At ordinary scales the accuracy switches change (almost) nothing; they matter for the
// precision scenes. A different offset moves shadow-ray origins, which may flip a few samples.
TEST(Reference, AccuracySwitchesAgreeOnOrdinaryScenes) {
    const Scene s = busyScene();
    const RenderOptions o = options(40, 30, 3);
    const Image base = rt::renderReference(s, o);
    auto pixelsOff = [&](RenderOptions changed) {
        const Image img = rt::renderReference(s, changed);
        int over = 0;
        for (std::size_t i = 0; i < base.rgb.size(); ++i)
            over += std::abs(base.rgb[i] - img.rgb[i]) > 1e-4f;
        return over;
    };
    RenderOptions plain = o, mt = o, fixed = o;
    plain.robustSphere = false, mt.watertight = false, fixed.offset = RenderOptions::Offset::Fixed;
    EXPECT_LE(pixelsOff(plain), 1);
    EXPECT_LE(pixelsOff(mt), 1);
    EXPECT_LE(pixelsOff(fixed), 40 * 30 / 50);
}

}  // namespace
