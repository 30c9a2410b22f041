// Hand-derived analytic cases: the centre pixel of tiny scenes whose colour follows in
// closed form from core/SHADING.md — a lit sphere (Blinn-Phong), a mirror, Fresnel at normal
// incidence, total internal reflection and a shadowed point. The expected values are computed
// here from the formulas, never rendered by the code under test, and every case must hold in
// every pipeline and at scales 1e-4, 1 and 1e5 (the offsets must not show).
#include <gtest/gtest.h>

#include <cmath>
#include <glm/glm.hpp>
#include <memory>
#include <string>

#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "core/scene_scale.h"
#include "pipelines/registry.h"
#include "test_device.h"

namespace rt {
namespace {

using glm::dvec3;

dvec3 d3(const dev::Float3& f) { return {f.x, f.y, f.z}; }

dev::Material material(dev::Float3 ambient, dev::Float3 diffuse, dev::Float3 specular) {
    dev::Material m{};
    m.ambient = ambient;
    m.diffuse = diffuse;
    m.specular = specular;
    m.exponent = 16.f;
    m.opacity = 1.f;
    m.ior = 1.f;
    return m;
}

Scene scene(dev::Material m, dev::Float3 camera, float pitch) {
    Scene s;
    s.name = "analytic";
    s.materials = {m};
    s.materialNames = {"m"};
    s.camera = {camera, 0.f, pitch, 0.6f, {0, 0}};
    return s;
}

// The centre ray of an odd-sized image: section 1 with Nc = (0, 0, D), yaw 0.
dvec3 centreDir(const Scene& s) {
    const double a = s.camera.pitch;
    return {0, std::sin(a), std::cos(a)};
}

// Section 9's sky gradient.
dvec3 sky(const Scene& s, dvec3 d) {
    const dvec3 h = d3(s.environment.horizon);
    return d.y >= 0 ? h + (d3(s.environment.zenith) - h) * d.y
                    : h + (d3(s.environment.ground) - h) * (-d.y);
}

// Section 7, written out again: Fresnel for cosI = -d.N, from n1 into n2.
double fresnel(double cosI, double n1, double n2) {
    const double sinT = n1 / n2 * std::sqrt(1 - cosI * cosI);
    if (sinT >= 1) return 1;
    const double cosT = std::sqrt(1 - sinT * sinT);
    const double rs = (n2 * cosI - n1 * cosT) / (n2 * cosI + n1 * cosT);
    const double rp = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    return (rs * rs + rp * rp) / 2;
}

// Renders s and its copies at 1e-4 and 1e5 with every pipeline; the centre pixel must be
// `expected` within float rounding.
void expectCentre(Scene s, int bounces, dvec3 expected, float shadowStrength = 1.f) {
    finalizeScene(s);
    RenderOptions o;
    o.width = 5;
    o.height = 5;
    o.bounces = bounces;
    o.shadowStrength = shadowStrength;
    const Scene copies[] = {s, scaleScene(s, 1e-4), scaleScene(s, 1e5)};
    const char* scales[] = {"1", "1e-4", "1e5"};
    for (int i = 0; i < 3; ++i)
        for (const std::string& k : pipelineRegistry().names()) {
            const Image img = makePipeline(k, &test::device())->render(copies[i], o);
            const float* c = img.pixel(2, 2);
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(c[ch], expected[ch], 1e-4)
                    << k << " at scale " << scales[i] << ", channel " << ch;
        }
}

// A sphere at distance 5 lit from above the camera: p = (0, 0, 4), N = (0, 0, -1).
TEST(Analytic, LitSphereCentreIsBlinnPhong) {
    Scene s = scene(material({0.05f, 0.1f, 0.02f}, {0.6f, 0.4f, 0.3f}, {0.3f, 0.3f, 0.5f}),
                    {0, 0, 0}, 0.f);
    s.spheres.push_back({{0, 0, 5}, 1.f, 0, {0, 0, 0}});
    s.lights.push_back({{0, 5, 0}, 0.f, {0.9f, 0.8f, 1.f}, 0.f});
    const dvec3 p(0, 0, 4), n(0, 0, -1), d(0, 0, 1);
    const dvec3 l = glm::normalize(dvec3(0, 5, 0) - p), h = glm::normalize(l - d);
    const dev::Material& m = s.materials[0];
    const dvec3 expected =
        d3(m.ambient) + d3(s.lights[0].color) * (d3(m.diffuse) * glm::dot(n, l) +
                                                 d3(m.specular) * std::pow(glm::dot(n, h), 16.0));
    expectCentre(s, 0, expected);
}

// A floor mirror (reflectance 0.7) seen from above at pitch -0.5: 0.3 of its ambient colour plus
// 0.7 of the sky in the reflected direction (0, sin 0.5, cos 0.5).
TEST(Analytic, MirrorReflectsTheSky) {
    dev::Material m = material({0.2f, 0.1f, 0.4f}, {0, 0, 0}, {0, 0, 0});
    m.reflectance = 0.7f;
    Scene s = scene(m, {0, 1, 0}, -0.5f);
    s.planes.push_back({{0, 1, 0}, 0.f, 0, {0, 0, 0}});
    const dvec3 d = centreDir(s), r(d.x, -d.y, d.z);
    expectCentre(s, 1, 0.3 * d3(m.ambient) + 0.7 * sky(s, r));
}

// A fully transparent pane (ior 1.5) facing the camera: F = ((1 - 1.5) / (1 + 1.5))^2 = 0.04 of
// the sky behind the camera, 0.96 of the sky straight through.
TEST(Analytic, FresnelAtNormalIncidence) {
    dev::Material m = material({0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0, 0, 0});
    m.opacity = 0.f;
    m.ior = 1.5f;
    Scene s = scene(m, {0, 0, 0}, 0.4f);
    const dvec3 d = centreDir(s);
    s.planes.push_back({{float(-d.x), float(-d.y), float(-d.z)}, -3.f, 0, {0, 0, 0}});
    const double f = std::pow((1 - 1.5) / (1 + 1.5), 2);
    EXPECT_NEAR(fresnel(1, 1, 1.5), f, 1e-15);
    expectCentre(s, 1, (1 - f) * sky(s, d) + f * sky(s, -d));
}

// Looking up at the underside of a glass plane (ior 1.5) from inside it. At pitch 0.3 the angle
// of incidence is 72.8 degrees, past the critical 41.8: all of the light is reflected, down
// into the ground colour. At pitch 1.2 (21.2 degrees) it refracts: Fresnel and Snell's law.
TEST(Analytic, TotalInternalReflectionAndRefractionFromInside) {
    dev::Material m = material({0.2f, 0.1f, 0.05f}, {0, 0, 0}, {0, 0, 0});
    m.opacity = 0.3f;
    m.ior = 1.5f;
    for (float pitch : {0.3f, 1.2f}) {
        Scene s = scene(m, {0, -1, 0}, pitch);
        s.planes.push_back({{0, 1, 0}, 0.f, 0, {0, 0, 0}});
        const dvec3 d = centreDir(s), n(0, -1, 0);  // n faces the ray
        const double cosI = -glm::dot(d, n), eta = 1.5;
        const double sinT = eta * std::sqrt(1 - cosI * cosI);
        const dvec3 reflected(d.x, -d.y, d.z);
        if (pitch < 1) {
            ASSERT_GE(sinT, 1) << "total internal reflection expected";
            expectCentre(s, 1, sky(s, reflected));
            continue;
        }
        ASSERT_LT(sinT, 1);
        const double f = fresnel(cosI, eta, 1);
        const dvec3 t = eta * d + (eta * cosI - std::sqrt(1 - sinT * sinT)) * n;
        const dvec3 through = 0.3 * d3(m.ambient) + 0.7 * sky(s, glm::normalize(t));
        expectCentre(s, 1, (1 - f) * through + f * sky(s, reflected));
    }
}

// A floor point straight below the light, with a ball between them: ambient only at full shadow
// strength, and (1 - 0.6) of the direct light at strength 0.6.
TEST(Analytic, ShadowedPointKeepsOnlyWhatTheShadowStrengthLeaves) {
    Scene s = scene(material({0.05f, 0.04f, 0.03f}, {0.7f, 0.6f, 0.5f}, {0.2f, 0.2f, 0.2f}),
                    {0, 1, -1}, float(-M_PI / 4));
    s.planes.push_back({{0, 1, 0}, 0.f, 0, {0, 0, 0}});
    s.spheres.push_back({{0, 2, 0}, 0.5f, 0, {0, 0, 0}});
    s.lights.push_back({{0, 4, 0}, 0.f, {1, 1, 1}, 0.f});
    const dev::Material& m = s.materials[0];
    expectCentre(s, 0, d3(m.ambient));
    const dvec3 d = glm::normalize(dvec3(0, -1, 1)), l(0, 1, 0), h = glm::normalize(l - d);
    const dvec3 direct = d3(m.diffuse) + d3(m.specular) * std::pow(h.y, 16.0);
    expectCentre(s, 0, d3(m.ambient) + 0.4 * direct, 0.6f);
}

}  // namespace
}  // namespace rt
