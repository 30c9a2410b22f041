// The NFF reader (core/nff_loader.cpp): a small file becomes exactly the scene docs/NFF.md
// says, the camera sees what NFF's viewpoint sees for any `up`, the SPD files load, and every
// malformed file fails with its one line naming the line and the reason.
#include "core/nff_loader.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "core/scene_loader.h"

namespace rt {
namespace {

constexpr float kNffDeg = 3.14159265358979f / 180.f;

void expectFloat3(const dev::Float3& got, dev::Float3 want, const char* what) {
    EXPECT_NEAR(got.x, want.x, 1e-6f) << what;
    EXPECT_NEAR(got.y, want.y, 1e-6f) << what;
    EXPECT_NEAR(got.z, want.z, 1e-6f) << what;
}

const char* const kSmallNff = R"(# a comment line
b 0.1 0.2 0.3
v
from 0 -5 1
at 0 0 1
up 0 0 1
angle 40
hither 0.5
resolution 160 120
l 1 2 3
l -1 -2 3 0.5 0.25 1
f 1 0.5 0.25 0.8 0.2 30 0 1
s 1 2 3 0.5
f 0.2 0.4 0.6 0.5 0.1 10 0.8 1.5
p 4
0 0 0
1 0 0
1 1 0
0 1 0

pp 3
0 0 1  0 0 1
1 0 1  0 0 1
0 1 1  0 1 1
f 1 0.5 0.25 0.8 0.2 30 0 1
c
0 0 0 1
0 0 2 1
)";

// z-up NFF (x, y, z) is rtlab's (x, z, y); triangles list their vertices 0, 2, 1.
TEST(NffLoader, SmallFileBecomesExactlyItsScene) {
    const Scene s = parseNff(kSmallNff, "small.nff", NffOptions{4});
    EXPECT_EQ(s.name, "small");
    expectFloat3(s.camera.position, {0, 1, -5}, "camera");
    EXPECT_FLOAT_EQ(s.camera.yaw, 0.f);
    EXPECT_FLOAT_EQ(s.camera.pitch, 0.f);
    EXPECT_FLOAT_EQ(s.camera.fovY, 40 * kNffDeg);
    EXPECT_EQ(s.defaults.width, 160);
    EXPECT_EQ(s.defaults.height, 120);
    for (const dev::Float3& c : {s.environment.zenith, s.environment.horizon, s.environment.ground})
        expectFloat3(c, {0.1f, 0.2f, 0.3f}, "background");

    ASSERT_EQ(s.lights.size(), 2u);
    const float k = 1 / std::sqrt(2.f);  // Haines: 1 / sqrt(number of lights)
    expectFloat3(s.lights[0].position, {1, 3, 2}, "light 0");
    expectFloat3(s.lights[0].color, {k, k, k}, "light 0 colour");
    expectFloat3(s.lights[1].position, {-1, 3, -2}, "light 1");
    expectFloat3(s.lights[1].color, {0.5f * k, 0.25f * k, k}, "light 1 colour");
    EXPECT_EQ(s.lights[1].radius, 0.f);

    ASSERT_EQ(s.materials.size(), 2u) << "the repeated 'f' is the first material again";
    EXPECT_EQ(s.materialNames, (std::vector<std::string>{"f0", "f1"}));
    const dev::Material& a = s.materials[0];
    expectFloat3(a.ambient, {0, 0, 0}, "ambient");
    expectFloat3(a.diffuse, {0.8f, 0.4f, 0.2f}, "Kd x colour");
    expectFloat3(a.specular, {0.2f, 0.2f, 0.2f}, "Ks, white");
    EXPECT_EQ(a.exponent, 30.f);
    EXPECT_FLOAT_EQ(a.reflectance, 0.2f);
    EXPECT_EQ(a.opacity, 1.f);
    EXPECT_EQ(a.ior, 1.f);
    EXPECT_EQ(a.pattern, RT_PATTERN_NONE);
    const dev::Material& g = s.materials[1];
    expectFloat3(g.diffuse, {0.1f, 0.2f, 0.3f}, "glass diffuse");
    EXPECT_FLOAT_EQ(g.opacity, 0.2f);
    EXPECT_FLOAT_EQ(g.ior, 1.5f);
    EXPECT_EQ(s.branching(), 2);

    ASSERT_EQ(s.spheres.size(), 1u);
    expectFloat3(s.spheres[0].center, {1, 3, 2}, "sphere");
    EXPECT_EQ(s.spheres[0].radius, 0.5f);
    EXPECT_EQ(s.spheres[0].material, 0);
    EXPECT_TRUE(s.planes.empty());

    // 2 (the quad's fan) + 1 (the patch) + 2 x 4 (the cylinder's quads).
    ASSERT_EQ(s.triangles.size(), 11u);
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_EQ(s.meshes[0].triangleCount, 11);
    const dev::Triangle& q0 = s.triangles[0];
    expectFloat3(q0.v0, {0, 0, 0}, "quad v0");
    expectFloat3(q0.v1, {1, 0, 1}, "quad v1");
    expectFloat3(q0.v2, {1, 0, 0}, "quad v2");
    for (const dev::Float3& n : {q0.n0, q0.n1, q0.n2}) expectFloat3(n, {0, 1, 0}, "quad normal");
    EXPECT_EQ(q0.material, 1);
    expectFloat3(s.triangles[1].v1, {0, 0, 1}, "second fan triangle");
    expectFloat3(s.triangles[1].v2, {1, 0, 1}, "second fan triangle");
    const dev::Triangle& pp = s.triangles[2];
    expectFloat3(pp.v0, {0, 1, 0}, "patch v0");
    expectFloat3(pp.v1, {0, 1, 1}, "patch v1");
    expectFloat3(pp.v2, {1, 1, 0}, "patch v2");
    expectFloat3(pp.n1, {0, std::sqrt(0.5f), std::sqrt(0.5f)}, "patch n1 (normalised)");
    expectFloat3(pp.n2, {0, 1, 0}, "patch n2");
    const dev::Triangle& c0 = s.triangles[3];
    expectFloat3(c0.v0, {0, 0, 1}, "cylinder v0");
    expectFloat3(c0.v1, {-1, 2, 0}, "cylinder v1");
    expectFloat3(c0.v2, {-1, 0, 0}, "cylinder v2");
    expectFloat3(c0.n0, {0, 0, 1}, "cylinder n0");
    expectFloat3(c0.n1, {-1, 0, 0}, "cylinder n1");
    EXPECT_EQ(c0.material, 0);
}

// NFF's front face (counter-clockwise as seen from it) stays the side whose e1 x e2 faces it.
TEST(NffLoader, PolygonFrontStaysOutside) {
    const Scene s = parseNff(kSmallNff, "small.nff", NffOptions{4});
    const dev::Triangle& t = s.triangles[0];
    const float e1[3] = {t.v1.x - t.v0.x, t.v1.y - t.v0.y, t.v1.z - t.v0.z};
    const float e2[3] = {t.v2.x - t.v0.x, t.v2.y - t.v0.y, t.v2.z - t.v0.z};
    EXPECT_GT(e1[2] * e2[0] - e1[0] * e2[2], 0.f) << "NFF +z (the quad's front) is rtlab's +y";
}

TEST(NffLoader, ConesTakeTheSegmentsAskedForAndDropDegenerateTriangles) {
    const std::string head =
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\n"
        "resolution 8 8\nf 1 1 1 1 0 0 0 1\n";
    EXPECT_EQ(parseNff(head + "c\n0 0 0 1\n0 1 0 1\n", "a.nff").triangles.size(), 32u);
    EXPECT_EQ(parseNff(head + "c\n0 0 0 1\n0 1 0 1\n", "a.nff", NffOptions{24}).triangles.size(),
              48u);
    // A true cone (apex radius 0): one triangle a segment, its normals leaning to the apex.
    const Scene cone = parseNff(head + "c\n0 0 0 1\n0 1 0 0\n", "a.nff", NffOptions{8});
    ASSERT_EQ(cone.triangles.size(), 8u);
    EXPECT_NEAR(cone.triangles[0].n0.y, std::sqrt(0.5f), 1e-6f);
}

// Spheres placed right of and above the view centre, in NFF's own sense (right = view x up,
// lib_create_view_matrix), land there in rtlab's camera (SHADING.md section 1) for any `up`.
TEST(NffLoader, CameraSeesWhatTheViewpointSees) {
    struct View {
        double from[3], at[3], up[3];
    };
    const View views[] = {
        {{0, 0, 5}, {0, 0, 0}, {0, 1, 0}},
        {{2.1, 1.3, 1.7}, {0, 0, 0}, {0, 0, 1}},  // balls
        {{1.02285, -3.17715, -2.17451}, {-0.0041, -0.0041, 0.2165}, {-0.8165, -0.8165, 0.8165}},
        {{1, 2, 3}, {0, 0, 0}, {0, 0, -1}},
        {{0, 4, 0}, {0, 0, 0}, {1, 1, 0}},  // up far from perpendicular to the view
    };
    for (const View& v : views) {
        auto vec = [](const double* p) { return std::array<double, 3>{p[0], p[1], p[2]}; };
        auto f = vec(v.at), u = vec(v.up);
        for (int i = 0; i < 3; ++i) f[i] -= v.from[i];
        auto norm = [](std::array<double, 3> a) {
            const double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            return std::array<double, 3>{a[0] / l, a[1] / l, a[2] / l};
        };
        auto cross = [](std::array<double, 3> a, std::array<double, 3> b) {
            return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                         a[0] * b[1] - a[1] * b[0]};
        };
        f = norm(f);
        const auto right = norm(cross(f, u));
        const auto up = cross(right, f);
        char text[1024];
        std::snprintf(text, sizeof text,
                      "v\nfrom %.9g %.9g %.9g\nat %.9g %.9g %.9g\nup %.9g %.9g %.9g\nangle 45\n"
                      "hither 1\nresolution 8 8\nf 1 1 1 1 0 0 0 1\n"
                      "s %.9g %.9g %.9g 0.1\ns %.9g %.9g %.9g 0.1\n",
                      v.from[0], v.from[1], v.from[2], v.at[0], v.at[1], v.at[2], v.up[0], v.up[1],
                      v.up[2], v.from[0] + 5 * f[0] + right[0], v.from[1] + 5 * f[1] + right[1],
                      v.from[2] + 5 * f[2] + right[2], v.from[0] + 5 * f[0] + up[0],
                      v.from[1] + 5 * f[1] + up[1], v.from[2] + 5 * f[2] + up[2]);
        const Scene s = parseNff(text, "view.nff");
        const double a = s.camera.pitch, b = s.camera.yaw;
        const double rx[3] = {std::cos(b), 0, -std::sin(b)};
        const double uy[3] = {-std::sin(a) * std::sin(b), std::cos(a), -std::sin(a) * std::cos(b)};
        const double fw[3] = {std::cos(a) * std::sin(b), std::sin(a), std::cos(a) * std::cos(b)};
        auto project = [&](const dev::Float3& p, const double* axis) {
            const double d[3] = {p.x - s.camera.position.x, p.y - s.camera.position.y,
                                 p.z - s.camera.position.z};
            return d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
        };
        const dev::Float3 r = s.spheres[0].center, t = s.spheres[1].center;
        EXPECT_NEAR(project(r, fw), 5, 1e-5) << text;
        EXPECT_NEAR(project(r, rx), 1, 1e-5) << "right of the centre: " << text;
        EXPECT_NEAR(project(r, uy), 0, 1e-5) << text;
        EXPECT_NEAR(project(t, rx), 0, 1e-5) << text;
        EXPECT_NEAR(project(t, uy), 1, 1e-5) << "above the centre: " << text;
    }
}

TEST(NffLoader, SphereflakeLoadsAsTheSpdWroteIt) {
    const Scene s = loadScene("scenes/spd/balls.nff");
    EXPECT_EQ(s.spheres.size(), 7381u);
    EXPECT_EQ(s.triangles.size(), 2u);  // the ground polygon
    ASSERT_EQ(s.lights.size(), 3u);
    EXPECT_FLOAT_EQ(s.lights[2].color.x, 1 / std::sqrt(3.f));
    EXPECT_EQ(s.defaults.width, 512);
    EXPECT_FLOAT_EQ(s.camera.fovY, 45 * kNffDeg);
    EXPECT_TRUE(s.notes.empty());
}

TEST(NffLoader, SceneLoaderTakesNffOfAnyCase) {
    EXPECT_TRUE(isNffFile("a/b.NFF"));
    EXPECT_FALSE(isNffFile("a/b.nff.json"));
}

struct BadNff {
    const char* body;  // after a valid viewpoint of 7 lines and a fill line (line 8)
    const char* error;
};

class NffRejects : public ::testing::TestWithParam<BadNff> {};

TEST_P(NffRejects, WithOneLineNamingTheLine) {
    const std::string text = std::string(
                                 "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\n"
                                 "resolution 64 64\nf 1 1 1 1 0 10 0 1\n") +
                             GetParam().body;
    try {
        parseNff(text, "bad.nff");
        FAIL() << "no error for " << GetParam().body;
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), std::string("bad.nff: ") + GetParam().error);
    }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, NffRejects,
    ::testing::Values(
        BadNff{"s 0 0 0\n", "line 9: truncated sphere 's': the file ends before its radius"},
        BadNff{"s 0 0 0\ns 1 1 1 1\n",
               "line 10: sphere 's' (of line 9): expected its radius, got 's'"},
        BadNff{"s 0 0 0 1 2\n",
               "line 9: unknown keyword '2' (NFF entities are v, b, l, f, s, p, "
               "pp, c and # comments)"},
        BadNff{"p 4\n0 0 0\n1 0 0\n",
               "line 9: truncated polygon 'p': the file ends before its vertex 3 of 4 x"},
        BadNff{"p 3\n0 0 0\ns 1 1 1 1\n1 1 0\n",
               "line 11: polygon 'p' (of line 9): expected its vertex 2 of 3 x, got 's'"},
        BadNff{"pp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 0\n",
               "line 12: polygon patch 'pp': vertex 3 of 3's normal is the zero vector"},
        BadNff{"c\n0 0 0 1\n", "line 9: truncated cone 'c': the file ends before its apex x"},
        BadNff{"c 0 0 0 1 0 0 0 2\n", "line 9: cone whose base and apex are the same point"},
        BadNff{"c\n0 0 0 0\n0 0 1 0\n", "line 9: cone whose radii are both 0"},
        BadNff{"tpp 3\n",
               "line 9: unknown keyword 'tpp' (NFF entities are v, b, l, f, s, p, pp, c and # "
               "comments)"},
        BadNff{"p 2\n0 0 0\n1 0 0\n", "line 9: polygon 'p' of 2 vertices (at least 3)"},
        BadNff{"p 3.5\n", "line 9: polygon 'p' of 3.5 vertices (at least 3)"},
        BadNff{"s 0 nan 0 1\n", "line 9: sphere 's': centre y 'nan' is not a finite 32-bit float"},
        BadNff{"s 0 1e39 0 1\n",
               "line 9: sphere 's': centre y '1e39' is not a finite 32-bit float"},
        BadNff{"s 0 0x 0 1\n", "line 9: sphere 's': expected its centre y, got '0x'"},
        BadNff{"s 0 0 0 0\n", "line 9: sphere of radius 0"},
        BadNff{"f 1 1 1 1 0 10 0.5 0\n",
               "line 9: a transmitting material (T > 0) needs an index of refraction > 0, got 0"},
        BadNff{"f 1 1 1 1 2 10 0 1\n", "line 9: Ks must be in [0, 1], got 2"},
        BadNff{"f 1 1 1 1 0 10 0\n", "line 9: truncated fill 'f': the file ends before its ior"},
        BadNff{"l 1 2\n", "line 9: truncated light 'l': the file ends before its position z"},
        BadNff{"v\n", "line 9: a second viewpoint ('v')"},
        BadNff{"b 0 0 -1\n", "line 9: background colour must be >= 0, got -1"}));

// Viewpoint errors: the file is the viewpoint alone.
TEST(NffLoader, RejectsBadViewpoints) {
    auto error = [](const std::string& text) {
        try {
            parseNff(text, "v.nff");
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("(no error)");
    };
    const std::string tail = "angle 45\nhither 1\nresolution 64 64\n";
    EXPECT_EQ(error("v\nfrom 1 2 3\nat 1 2 3\nup 0 1 0\n" + tail),
              "v.nff: line 3: viewpoint: 'from' and 'at' are the same point");
    EXPECT_EQ(error("v\nfrom 0 0 5\nat 0 0 0\nup 0 0 1\n" + tail),
              "v.nff: line 4: viewpoint: 'up' is parallel to the view direction");
    EXPECT_EQ(error("v\nfrom 0 0 5\nat 0 0 0\nup 0 0 0\n" + tail),
              "v.nff: line 4: viewpoint: 'up' is the zero vector");
    EXPECT_EQ(error("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 180\nhither 1\nresolution 8 8\n"),
              "v.nff: line 5: viewpoint: 'angle' must be in (0, 180) degrees, got 180");
    EXPECT_EQ(error("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\n"),
              "v.nff: line 1: truncated viewpoint: the file ends before its 'angle'");
    EXPECT_EQ(error("v\nfrom 0 0 5\nup 0 1 0\n"),
              "v.nff: line 3: viewpoint: expected 'at', got 'up'");
    EXPECT_EQ(error("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 0 64\n"),
              "v.nff: line 7: viewpoint: 'resolution' must be integers in 1..16384, got 0");
    EXPECT_EQ(error("# only a comment\ns 0 0 0 1\n"),
              "v.nff: line 2: no viewpoint ('v') in the file");
    std::string lights = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\n" + tail;
    for (int i = 0; i <= RT_MAX_LIGHTS; ++i) lights += "l 0 " + std::to_string(i) + " 0\n";
    EXPECT_EQ(error(lights), "v.nff: line 24: more than 16 lights (rtlab's limit, RT_MAX_LIGHTS)");
}

TEST(NffLoader, ObjectBeforeAnyFillIsWhiteWithANote) {
    const Scene s = parseNff(
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\n"
        "resolution 8 8\ns 0 0 0 -1\n",
        "n.nff");
    ASSERT_EQ(s.materials.size(), 1u);
    expectFloat3(s.materials[0].diffuse, {1, 1, 1}, "white");
    EXPECT_EQ(s.spheres[0].radius, 1.f);
    ASSERT_EQ(s.notes.size(), 2u);
    EXPECT_EQ(s.notes[0],
              "n.nff: line 8: an object before any fill material 'f': white and diffuse");
}

}  // namespace
}  // namespace rt
