// Megakernel: accuracy against the double-precision CPU reference on every standard
// scene, single rays through the device intersection code, and the per-scene feature defines.
#include "megakernel/megakernel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "core/kernel_sources.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "megakernel/megakernel_options.h"
#include "test_device.h"
#include "test_images.h"
#include "test_scenes.h"

namespace rt {
namespace {

using test::kScenes;
using test::load;

RenderOptions small(const Scene& scene, int bounces) {
    RenderOptions o = scene.defaults;
    o.width = 80;
    o.height = 60;
    o.bounces = bounces;
    o.shadowSamples = std::min(o.shadowSamples, 4);
    o.aa = 1;
    return o;
}

// The accuracy bar: >= 99.9% of pixels within 2/255, mean absolute error <= 0.5/255,
// on linear values clamped to [0, 1]. At 80x60 one pixel is 0.02% of the image, so 99.9% allows
// four outliers: pixels whose ray grazes an edge, where float and double pick different objects.
class MegaVsCpu : public ::testing::TestWithParam<std::tuple<const char*, int>> {};

TEST_P(MegaVsCpu, WithinAccuracyBar) {
    auto [name, bounces] = GetParam();
    Scene scene = load(name);
    RenderOptions o = small(scene, bounces);
    MegakernelPipeline mega(test::device());
    Image gpu = mega.render(scene, o);
    Image cpu = renderReference(scene, o);
    ImageDiff d = compareImages(gpu, cpu, 2.0 / 255.0);
    EXPECT_GE(d.fractionWithin, 0.999) << name << " B=" << bounces << ": " << d.pixelsOver
                                       << " pixels over 2/255, max " << d.maxAbs * 255 << "/255";
    EXPECT_LE(d.meanAbs, 0.5 / 255.0) << name << " B=" << bounces;
}

INSTANTIATE_TEST_SUITE_P(StandardScenes, MegaVsCpu,
                         ::testing::Combine(::testing::ValuesIn(kScenes),
                                            ::testing::Values(0, 2, 5)),
                         [](const auto& info) {
                             return std::string(std::get<0>(info.param)) + "_B" +
                                    std::to_string(std::get<1>(info.param));
                         });

// Every standard scene at every bounce limit 0..8 is rendered by the megakernel in
// tests/wavefront_test.cpp (WaveVsMega), which also checks the pixels are finite.

// Both layouts compute the same Whitted sum; they differ only in summation order.
TEST(Megakernel, WeightedLayoutMatchesTree) {
    for (const char* name : {"spheres", "cornell", "shadows"}) {
        Scene scene = load(name);
        RenderOptions o = small(scene, 4);
        MegakernelPipeline mega(test::device());
        Image tree = mega.render(scene, o);
        setMegaLayout(o, MegaLayout::Weighted);
        Image weighted = mega.render(scene, o);
        ImageDiff d = compareImages(tree, weighted, 1e-4, false);
        EXPECT_LE(d.maxAbs, 1e-4) << name;
    }
}

// The register cap is NVIDIA's compiler option: it reaches that compiler and no other, and it
// changes how the kernel is compiled, never what it computes.
TEST(Megakernel, RegisterCapIsNvidiaOnlyAndKeepsTheImage) {
    Scene scene = load("cornell");
    RenderOptions o = small(scene, 4);
    setMegaLayout(o, MegaLayout::Weighted);
    MegakernelPipeline mega(test::device());
    EXPECT_TRUE(mega.buildOptions(o).empty());
    const Image plain = mega.render(scene, o);
    setMegaMaxRegisters(o, 64);
    EXPECT_EQ(megaMaxRegisters(o), 64);
    EXPECT_EQ(mega.buildOptions(o), test::device().device().nvidia()
                                        ? std::vector<std::string>{"-cl-nv-maxrregcount=64"}
                                        : std::vector<std::string>{});
    const Image capped = mega.render(scene, o);
    EXPECT_TRUE(test::sameBits(plain, capped));
}

TEST(Megakernel, RejectsTreeTooBigForPrivateMemory) {
    Scene scene = load("spheres");  // has glass: C = 2
    ASSERT_EQ(scene.branching(), 2);
    RenderOptions o = small(scene, 14);
    MegakernelPipeline mega(test::device());
    try {
        mega.render(scene, o);
        FAIL() << "bounce limit 14 with C = 2 must not fit";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("--bounces 14"), std::string::npos) << msg;
        EXPECT_NE(msg.find("highest bounce limit that fits is 11"), std::string::npos) << msg;
        EXPECT_NE(msg.find("--layout weighted"), std::string::npos) << msg;
    }
    setMegaLayout(o, MegaLayout::Weighted);  // the weighted stack holds only B + 1 rays
    o.width = 8;
    o.height = 6;
    EXPECT_NO_THROW(mega.render(scene, o));
}

TEST(Megakernel, AdaptiveAaOnlyTouchesEdges) {
    Scene scene = load("spheres");
    RenderOptions o = small(scene, 2);
    MegakernelPipeline mega(test::device());
    Image one = mega.render(scene, o);
    o.aa = 3;
    Image full = mega.render(scene, o);
    o.adaptiveAa = true;
    Image adaptive = mega.render(scene, o);
    // Adaptive equals the centre sample on flat regions and the full grid on edges.
    long long same1 = 0, sameFull = 0, n = one.width * one.height;
    for (long long p = 0; p < n; ++p) {
        bool eq1 = true, eqF = true;
        for (int c = 0; c < 3; ++c) {
            eq1 &= adaptive.rgb[p * 3 + c] == one.rgb[p * 3 + c];
            eqF &= adaptive.rgb[p * 3 + c] == full.rgb[p * 3 + c];
        }
        same1 += eq1;
        sameFull += eqF && !eq1;
        EXPECT_TRUE(eq1 || eqF) << "pixel " << p;
    }
    EXPECT_GT(same1, n / 2);
    EXPECT_GT(sameFull, 0);
    // And it matches the CPU reference's adaptive mode.
    Image cpu = renderReference(scene, o);
    EXPECT_GE(compareImages(adaptive, cpu, 2.0 / 255.0).fractionWithin, 0.995);
}

// ---- single rays through the device code ----

std::vector<float> runSpheres(bool robust, const std::vector<float>& rays) {
    ClContext& cl = test::device();
    std::vector<std::string> defs;
    if (robust) defs.push_back("RT_ROBUST_SPHERE");
    cl::Program p = cl.program("probe.cl", defs);
    Kernel k(p, "Probe_Sphere");
    size_t n = rays.size() / 10;
    cl::Buffer in(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, rays.size() * 4,
                  const_cast<float*>(rays.data()));
    cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, n * 4);
    k.set("in", in).set("t", out);
    cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(n));
    std::vector<float> t(n);
    cl.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * 4, t.data());
    return t;
}

// Unit spheres 5,000 to 20,000 units away, hit by rays between 0.1 and 0.9 radii off-centre:
// b^2 - 4c cancels catastrophically in float (both terms are ~1e9 with a float spacing of 64,
// the true difference under 4), so the plain quadratic misses about a third of them.
TEST(DeviceRays, RobustSphereHitsWherePlainMisses) {
    std::mt19937 rng(1);
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> dist(5000, 20000), offset(0.1, 0.9);
    std::vector<float> rays;
    std::vector<double> expected;
    const int n = 256;
    for (int i = 0; i < n; ++i) {
        glm::dvec3 d = glm::normalize(glm::dvec3(gauss(rng), gauss(rng), gauss(rng)));
        glm::dvec3 side = glm::normalize(glm::cross(d, glm::dvec3(0.3, 0.5, 0.8)));
        glm::vec3 df(d), c(dist(rng) * d + offset(rng) * side);
        rays.insert(rays.end(), {0.f, 0.f, 0.f, df.x, df.y, df.z, c.x, c.y, c.z, 1.f});
        // Exact answer for the float inputs.
        glm::dvec3 dd = glm::normalize(glm::dvec3(df)), cc(c);
        double along = glm::dot(dd, cc);
        double perp2 = glm::dot(cc - along * dd, cc - along * dd);
        expected.push_back(along - std::sqrt(1.0 - perp2));
    }
    std::vector<float> plain = runSpheres(false, rays), robust = runSpheres(true, rays);
    int plainMisses = 0;
    for (int i = 0; i < n; ++i) {
        ASSERT_GT(robust[i], 0.f) << "robust test missed ray " << i;
        EXPECT_NEAR(robust[i], expected[i], 1e-2) << "ray " << i;
        if (plain[i] < 0.f) ++plainMisses;
    }
    EXPECT_GT(plainMisses, n / 10) << "the plain quadratic should lose many of these rays";
    RecordProperty("plain_misses", plainMisses);
    // Close to the camera both agree.
    std::vector<float> nearRays = {0.3f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 5.f, 1.f};
    EXPECT_NEAR(runSpheres(false, nearRays)[0], runSpheres(true, nearRays)[0], 1e-5);
}

// A closed icosphere; rays from its centre aimed exactly at points on shared edges. Every such
// ray must leave through some triangle; a ray that hits none has leaked through a crack.
int countLeaks(bool watertight) {
    // Icosahedron subdivided once, scaled and shifted to awkward float coordinates.
    const float t = (1.f + std::sqrt(5.f)) / 2.f;
    std::vector<glm::vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<int> f = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                          4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                          6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
    const glm::vec3 centre(3.1f, -7.3f, 11.7f);
    const float scale = 3.7f;
    std::vector<float> tris;
    for (size_t i = 0; i < f.size(); ++i) {
        glm::vec3 p = centre + scale * glm::normalize(v[f[i]]);
        tris.insert(tris.end(), {p.x, p.y, p.z});
    }
    std::vector<float> rays;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (size_t tri = 0; tri < f.size() / 3; ++tri)
        for (int e = 0; e < 3; ++e)
            for (int k = 0; k < 40; ++k) {
                const float* a = &tris[tri * 9 + e * 3];
                const float* b = &tris[tri * 9 + ((e + 1) % 3) * 3];
                float s = u(rng);
                glm::vec3 target(a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]),
                                 a[2] + s * (b[2] - a[2]));
                glm::vec3 origin = centre + glm::vec3(u(rng), u(rng), u(rng)) * 0.01f;
                glm::vec3 d = glm::normalize(target - origin);
                rays.insert(rays.end(), {origin.x, origin.y, origin.z, d.x, d.y, d.z});
            }
    ClContext& cl = test::device();
    std::vector<std::string> defs = {"RT_HAS_TRIANGLES"};
    if (watertight) defs.push_back("RT_WATERTIGHT");
    cl::Program p = cl.program("probe.cl", defs);
    Kernel k(p, "Probe_TriangleHits");
    size_t n = rays.size() / 6;
    cl::Buffer rb(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, rays.size() * 4,
                  rays.data());
    cl::Buffer tb(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, tris.size() * 4,
                  tris.data());
    cl::Buffer hb(cl.context(), CL_MEM_WRITE_ONLY, n * 4);
    k.set("rays", rb).set("tris", tb).set("count", cl_int(tris.size() / 9)).set("hits", hb);
    cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(n));
    std::vector<int> hits(n);
    cl.queue().enqueueReadBuffer(hb, CL_TRUE, 0, n * 4, hits.data());
    return int(std::count(hits.begin(), hits.end(), 0));
}

TEST(DeviceRays, WatertightLeaksNoRayThroughSharedEdges) {
    int mt = countLeaks(false), wt = countLeaks(true);
    EXPECT_EQ(wt, 0);
    EXPECT_GT(mt, 0) << "Moller-Trumbore was expected to leak some edge rays";
    RecordProperty("moller_trumbore_leaks", mt);
}

// ---- model no more than the scene needs ----

TEST(FeatureDefines, FollowTheScene) {
    Scene spheres = load("spheres");
    auto d = MegakernelPipeline::defines(spheres, spheres.defaults);
    auto has = [&](const std::string& s) { return std::find(d.begin(), d.end(), s) != d.end(); };
    EXPECT_TRUE(has("RT_HAS_SPHERES"));
    EXPECT_FALSE(has("RT_HAS_TRIANGLES"));
    EXPECT_TRUE(has("RT_BRANCH=2"));
    Scene shadows = load("shadows");  // no transparent material
    auto ds = featureDefines(shadows, shadows.defaults);
    EXPECT_NE(std::find(ds.begin(), ds.end(), "RT_BRANCH=1"), ds.end());
}

// The bounce limit reaches a program's defines only where a private array is sized by it: the
// megakernel's whole tree, and its stack of pending rays when the scene refracts (C = 2; at C = 1
// the stack holds one ray whatever B is).
TEST(FeatureDefines, BounceLimitOnlySizesPrivateArrays) {
    Scene spheres = load("spheres");  // refracts: C = 2
    Scene shadows = load("shadows");  // C = 1
    auto withBounces = [](const Scene& s, MegaLayout layout, int b) {
        RenderOptions o = s.defaults;
        setMegaLayout(o, layout);
        o.bounces = b;
        return o;
    };
    using L = MegaLayout;
    EXPECT_EQ(featureDefines(spheres, withBounces(spheres, L::Tree, 2)),
              featureDefines(spheres, withBounces(spheres, L::Tree, 6)));
    EXPECT_NE(MegakernelPipeline::defines(spheres, withBounces(spheres, L::Tree, 2)),
              MegakernelPipeline::defines(spheres, withBounces(spheres, L::Tree, 6)));
    EXPECT_NE(MegakernelPipeline::defines(spheres, withBounces(spheres, L::Weighted, 2)),
              MegakernelPipeline::defines(spheres, withBounces(spheres, L::Weighted, 6)));
    EXPECT_EQ(MegakernelPipeline::defines(shadows, withBounces(shadows, L::Weighted, 2)),
              MegakernelPipeline::defines(shadows, withBounces(shadows, L::Weighted, 6)));
    auto tree = MegakernelPipeline::defines(spheres, withBounces(spheres, L::Tree, 3));
    EXPECT_NE(std::find(tree.begin(), tree.end(), "RT_TREE_NODES=15"), tree.end());
    auto weighted = MegakernelPipeline::defines(spheres, withBounces(spheres, L::Weighted, 3));
    EXPECT_NE(std::find(weighted.begin(), weighted.end(), "RT_STACK_SIZE=4"), weighted.end());
}

// The spheres-only program contains no triangle intersection: a probe kernel that calls it does
// not even compile with that scene's defines, and compiles with the mesh scene's.
TEST(FeatureDefines, SpheresOnlyProgramHasNoTriangleCode) {
    ClContext& cl = test::device();
    std::string probe =
        "\nkernel void Probe_Triangle(global float* out) { float2 uv; Ray r = makeRay((float3)(0),"
        " (float3)(0, 0, 1)); out[0] = Triangle_Intersect(r, (float3)(0), (float3)(1, 0, 0),"
        " (float3)(0, 1, 0), INFINITY, &uv); }\n";
    std::string source = KernelSources().resolve("megakernel.cl") + probe;
    auto build = [&](const Scene& scene) {
        std::string options = "-cl-std=CL1.2";
        for (const std::string& d : MegakernelPipeline::defines(scene, scene.defaults))
            options += " -D" + d;
        cl::Program p(cl.context(), source);
        try {
            p.build({cl.device().device}, options.c_str());
            return true;
        } catch (const cl::Error&) {
            return false;
        }
    };
    EXPECT_FALSE(build(load("spheres")));
    EXPECT_TRUE(build(load("mesh")));
}

}  // namespace
}  // namespace rt
