// Stability: the numerical stress suite asserts the robust methods' figures and records
// the plain methods' (RecordProperty, in the gtest XML); garbage geometry is rejected with one
// clear line or renders without a NaN pixel; device limits end in a clear error. The cases and
// their probe kernels are those of rtlab-stress (stress/stress.h, core/cl/probe.cl), linked
// here so the tool and the test cannot drift apart; the tests use fewer rays.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "megakernel/megakernel.h"
#include "pipelines/registry.h"
#include "scratch_dir.h"
#include "stress/stress.h"
#include "test_device.h"
#include "wavefront/tree/wavefront.h"

namespace rt::stress {
namespace {

namespace fs = std::filesystem;

void record(const std::string& key, const Counts& c) {
    ::testing::Test::RecordProperty(key, std::to_string(c.bad) + "/" + std::to_string(c.rays));
}

const dvec3 kFar(148376, 1234, -223423);  // Embree's watertightness position

// ---- (a) ----
TEST(Stability, ClosedMeshFarFromTheOriginDoesNotLeak) {
    // 32 x 64 segments and 20,000 random rays keep this short on a CPU device; with so few
    // rays one miss already breaks the bar (5e-5), so it is "no miss" here. rtlab-stress runs
    // 200,000 rays at 64 x 128.
    for (dvec3 c : {dvec3(0), kFar}) {
        LeakResult wt = leaks(test::device(), true, c, 20000, 32);
        EXPECT_LE(wt.random.rate(), 2e-5) << "Embree's bar, centre x=" << c.x;
        EXPECT_EQ(wt.edges.bad, 0) << "rays through shared edges leaked, centre x=" << c.x;
        EXPECT_EQ(wt.vertices.bad, 0) << "rays through vertices leaked, centre x=" << c.x;
        LeakResult mt = leaks(test::device(), false, c, 20000, 32);
        std::string at = c.x == 0 ? "origin" : "far";
        record("mt_" + at + "_random_leaks", mt.random);
        record("mt_" + at + "_edge_leaks", mt.edges);
        record("mt_" + at + "_vertex_leaks", mt.vertices);
        record("wt_" + at + "_random_leaks", wt.random);
    }
}

// ---- (b) ----
TEST(Stability, TinySphereFarAwayIsHitByTheRobustTest) {
    SphereResult robust = tinySpheres(test::device(), true, 1e3, 1e-2, 4000);
    EXPECT_EQ(robust.misses.bad, 0);
    EXPECT_EQ(robust.falseHits.bad, 0);
    SphereResult plain = tinySpheres(test::device(), false, 1e3, 1e-2, 4000);
    record("plain_misses", plain.misses);
    record("plain_false_hits", plain.falseHits);
    // Whether the plain quadratic fails here depends on how the device compiler evaluates it
    // (contraction, fast-math defaults): recorded and reported, not asserted.
    if (plain.misses.bad + plain.falseHits.bad == 0)
        std::printf("note: the plain sphere test had no misses or false hits on %s\n",
                    test::device().device().name.c_str());
}

// ---- (c) ----
TEST(Stability, ScaledAndBoundOffsetsHaveNoAcneAtSmallAndLargeScales) {
    for (double s : {1e-3, 1e5})
        for (RenderOptions::Offset off :
             {RenderOptions::Offset::Scaled, RenderOptions::Offset::Bound}) {
            AcneResult a = acne(test::device(), s, off, 400, 32);
            std::string at = std::string(" with the ") + offsetName(off) + " offset at scale " +
                             std::to_string(s);
            EXPECT_GT(a.meshOut.rays, 1000) << at;
            EXPECT_GT(a.sphereOut.rays, 1000) << at;
            EXPECT_EQ(a.meshOut.bad, 0) << "outward acne on the mesh" << at;
            EXPECT_EQ(a.meshIn.bad, 0) << "inward acne on the mesh" << at;
            EXPECT_EQ(a.meshEscape.bad, 0) << "refraction rays pushed out of the mesh" << at;
            EXPECT_EQ(a.sphereOut.bad, 0) << "outward acne on the sphere" << at;
            EXPECT_EQ(a.sphereIn.bad, 0) << "inward acne on the sphere" << at;
            EXPECT_EQ(a.sphereEscape.bad, 0) << "refraction rays pushed out of the sphere" << at;
        }
    for (double s : {1e-3, 1e5}) {
        AcneResult f = acne(test::device(), s, RenderOptions::Offset::Fixed, 400, 32);
        std::string key = s < 1 ? "fixed_1e-3_" : "fixed_1e5_";
        record(key + "mesh_out_acne", f.meshOut);
        record(key + "mesh_in_acne", f.meshIn);
        record(key + "sphere_out_acne", f.sphereOut);
        record(key + "mesh_escaped", f.meshEscape);
    }
}

// The bound offset is scale-free: no acne and no escapes from 1e-8 to 1e8.
TEST(Stability, BoundOffsetHasNoAcneAtAnyScale) {
    for (double s : {1e-8, 1e-5, 1.0, 1e3, 1e8}) {
        AcneResult a = acne(test::device(), s, RenderOptions::Offset::Bound, 200, 32);
        long long bad = a.meshOut.bad + a.meshIn.bad + a.meshEscape.bad + a.sphereOut.bad +
                        a.sphereIn.bad + a.sphereEscape.bad;
        EXPECT_GT(a.meshOut.rays + a.sphereOut.rays, 1000) << "scale " << s;
        EXPECT_EQ(bad, 0) << "scale " << s;
    }
}

TEST(Stability, FixedEpsilonHasAcneFarFromTheOrigin) {
    AcneResult f = acne(test::device(), 1e5, RenderOptions::Offset::Fixed, 400, 32);
    EXPECT_GT(f.meshOut.rate() + f.sphereOut.rate(), 0.01) << "the report's epsilon at 1e5";
}

// pbrt-v4's Triangle.Reintersect with the scaled and the bound offset, at uniform scales
// 1e-8..1e8: 0 re-hits. (Mixed scales, one triangle spanning 1e-8..1e8, are recorded only: pbrt
// passes them because its triangle test also rejects t below t's own error bound; see
// results/*/stability.md.)
TEST(Stability, ReintersectHasNoRehitsAtEveryUniformScale) {
    for (RenderOptions::Offset off : {RenderOptions::Offset::Scaled, RenderOptions::Offset::Bound})
        for (double e : {-8.0, -3.0, 0.0, 5.0, 8.0}) {
            ReintersectResult r = reintersect(test::device(), off, e, e, false, 200, 200);
            EXPECT_LT(r.missed, 20) << offsetName(off) << " scale 1e" << e;
            EXPECT_EQ(r.rehits.bad, 0)
                << offsetName(off) << " scale 1e" << e << ": " << r.withRehits << " triangles";
        }
    ReintersectResult mixed =
        reintersect(test::device(), RenderOptions::Offset::Scaled, -8, 8, true, 200, 200);
    record("scaled_mixed_rehits", mixed.rehits);
    ReintersectResult bound =
        reintersect(test::device(), RenderOptions::Offset::Bound, -8, 8, true, 200, 200);
    record("bound_mixed_rehits", bound.rehits);
    ReintersectResult fixed =
        reintersect(test::device(), RenderOptions::Offset::Fixed, 5, 5, false, 200, 200);
    record("fixed_1e5_rehits", fixed.rehits);
}

// ---- (d) ----
TEST(Stability, RefractionAtCriticalAngleIsTotalAndFinite) {
    CriticalResult c = criticalAngle(test::device());
    EXPECT_EQ(c.nonFinite, 0);
    EXPECT_EQ(c.inconsistent, 0) << "no refracted ray but F < 1, or F outside [0, 1]";
    EXPECT_EQ(c.nonUnit, 0);
    EXPECT_GT(c.tirDevice, 0);
    EXPECT_LT(c.tirDevice, c.cases);
    ::testing::Test::RecordProperty("tir_differs_from_double", std::to_string(c.disagree));
    // The double reference at exactly the critical angle: a tangent ray or TIR, and F = 1.
    for (double ior : {1.1, 1.5, 2.42}) {
        double theta = std::asin(1.0 / ior);
        dvec3 d(std::sin(theta), -std::cos(theta), 0);
        auto t = ref::refract(d, dvec3(0, 1, 0), ior);
        if (t) EXPECT_NEAR(t->y, 0.0, 1e-6) << ior;
        EXPECT_NEAR(ref::fresnel(std::cos(theta), ior, 1.0), 1.0, 1e-6) << ior;
    }
}

TEST(Stability, GrazingRaysHitAndCoplanarRaysMiss) {
    std::vector<Counts> wt = grazing(test::device(), true, 256);
    std::vector<Counts> mt = grazing(test::device(), false, 256);
    EXPECT_EQ(wt[0].bad, 0) << "a ray in the triangle's plane hit it (watertight)";
    EXPECT_EQ(mt[0].bad, 0) << "a ray in the triangle's plane hit it (Moller-Trumbore)";
    // The conservative t > 0 (core/SHADING.md section 3) cannot certify a hit's sign once the
    // triangle's projection is thinner than its edge functions' rounding: from 10 units away,
    // at elevations of 1e-5 rad and below (a hundredth of a pixel of a 1080p frame at 60
    // degrees; some rays at 1e-5, every ray from 1e-6): such rays are recorded, not required.
    for (int k = 1; k <= 4; ++k)
        EXPECT_EQ(wt[k].bad, 0) << "watertight missed rays at elevation 1e-" << k;
    for (int k = 1; k <= 7; ++k) {
        record("wt_grazing_1e-" + std::to_string(k) + "_misses", wt[k]);
        record("mt_grazing_1e-" + std::to_string(k) + "_misses", mt[k]);
    }
}

// A camera a hair above a large triangulated floor and a plane, looking along them.
TEST(Stability, GrazingViewRendersFinite) {
    Scene s = emptyScene("grazing");
    s.materials.push_back(material(0.3f, 1.5f, 0.f));
    const float L = 1e4f;
    s.triangles.push_back(
        {{-L, 0, -L}, {L, 0, -L}, {L, 0, L}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, 1, 0});
    s.triangles.push_back(
        {{-L, 0, -L}, {L, 0, L}, {-L, 0, L}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, 1, 0});
    s.planes.push_back({{0, 1, 0}, -1e-6f, 0, {0, 0, 0}});
    s.spheres.push_back({{0, 1, 50}, 1.f, 1, {0, 0, 0}});
    s.lights.push_back({{0, 3, 10}, 0.f, {1, 1, 1}, 0.f});
    s.camera = {{0, 1e-4f, 0}, 0.f, 0.f, 0.5f, {0, 0}};
    finalizeScene(s);
    RenderOptions o;
    o.width = 32;
    o.height = 24;
    o.bounces = 4;
    for (std::string k : rt::pipelineRegistry().names())
        for (bool robust : {false, true}) {
            o.watertight = o.robustSphere = robust;
            o.offset = robust ? RenderOptions::Offset::Bound : RenderOptions::Offset::Fixed;
            Image img = makePipeline(k, &test::device())->render(s, o);
            for (float v : img.rgb) ASSERT_TRUE(std::isfinite(v)) << k;
        }
}

// ---- (e) ----
TEST(Stability, NestedDielectricsMatchTheReference) {
    for (std::string k : rt::pipelineRegistry().names(true)) {
        NestedResult n = nested(test::device(), k, 32, 24, 6);
        EXPECT_EQ(n.nonFinite, 0) << k;
        EXPECT_GE(double(n.within) / double(n.pixels), 0.99)
            << k << ": max " << n.maxAbs * 255 << "/255";
    }
}

// ---- (f) ----
TEST(Stability, NanAndInfRaysReturnWithoutBadHits) {
    for (RenderOptions::Accel a : {RenderOptions::Accel::None, RenderOptions::Accel::Bv,
                                   RenderOptions::Accel::Grid, RenderOptions::Accel::Bvh}) {
        NanResult n = nanRays(test::device(), a);
        EXPECT_EQ(n.badHits, 0) << accelName(a);
        ::testing::Test::RecordProperty(std::string("nan_colours_") + accelName(a),
                                        std::to_string(n.nanPixels) + "/" + std::to_string(n.rays));
    }
}

// ---- garbage geometry ----
fs::path writeFile(const std::string& name, const std::string& text) {
    fs::path dir = rt::test::scratchPath("stability/");
    std::ofstream(dir / name) << text;
    return dir / name;
}

void expectNoNan(const Scene& scene, const std::string& what) {
    RenderOptions o = scene.defaults;
    o.width = 24;
    o.height = 18;
    o.bounces = 3;
    o.shadowSamples = std::min(o.shadowSamples, 4);
    for (RenderOptions::Accel a : {RenderOptions::Accel::None, RenderOptions::Accel::Bv,
                                   RenderOptions::Accel::Grid, RenderOptions::Accel::Bvh}) {
        o.accel = a;
        for (std::string k : {"cpu", "mega", "wave"}) {
            Image img = makePipeline(k, &test::device())->render(scene, o);
            size_t nan = 0;
            for (float v : img.rgb) nan += !std::isfinite(v);
            EXPECT_EQ(nan, 0u) << what << ": " << k << " --accel " << accelName(a);
        }
    }
}

void expectRejected(const fs::path& file, const std::string& reason) {
    try {
        loadScene(file);
        ADD_FAILURE() << file << " loaded";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find(file.filename().string()), std::string::npos) << msg;
        EXPECT_NE(msg.find(reason), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
    }
}

TEST(Stability, NonFiniteAndOutOfRangeGeometryIsRejected) {
    expectRejected(writeFile("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"), "bad number");
    expectRejected(writeFile("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n"), "bad number");
    expectRejected(writeFile("big.obj", "v 0 0 0\nv 1 1e39 0\nv 0 1 0\nf 1 2 3\n"), "finite");
    expectRejected(writeFile("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "out of range");
    expectRejected(writeFile("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n"), "before");
    expectRejected(writeFile("normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n"),
                   "out of range");
    expectRejected(writeFile("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"), "degenerate");
    // Finite vertices whose transform overflows float.
    writeFile("tri.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n");
    expectRejected(writeFile("overflow.json",
                             R"({"camera": {"position": [0, 0, -5]}, "materials": {"m": {}},
                                 "meshes": [{"file": "tri.obj", "material": "m",
                                             "transform": {"scale": 1e10}}]})"),
                   "non-finite");
    // Hand-built scenes go through finalizeScene, which checks what the loader would.
    Scene s = emptyScene("nan-vertex");
    s.triangles.push_back({{0, 0, 4}, {1, NAN, 4}, {0, 1, 4}, {}, {}, {}, 0, 0});
    EXPECT_THROW(finalizeScene(s), Error);
}

TEST(Stability, DegenerateAndExtremeGeometrySurvivesWithoutNan) {
    // Collinear, repeated-vertex, 1e-30-sized and opposite-normal triangles beside a good one.
    fs::path obj = writeFile("degenerate.obj",
                             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 1e-30 0 0\nv 0 1e-30 0\n"
                             "vn 0 0 1\nvn 0 0 -1\n"
                             "f 1//1 2//2 3//1\nf 1//1 2//1 4//1\nf 1//1 1//1 3//1\n"
                             "f 1//1 5//1 6//2\n");
    expectNoNan(loadScene(obj), "degenerate.obj");
    // Spheres, planes and lights at the edge of float range, a denormal radius.
    fs::path json = writeFile("extreme.json", R"({
        "camera": {"position": [0, 1, -5]},
        "materials": {"m": {"reflectance": 0.3}, "g": {"opacity": 0.2, "ior": 1.5}},
        "spheres": [{"center": [0, 0, 3e38], "radius": 3e38, "material": "m"},
                    {"center": [0, 1, 0], "radius": 1e-38, "material": "g"},
                    {"center": [1, 1, 0], "radius": 1e-20, "material": "m"},
                    {"center": [-3e38, 0, 0], "radius": 1e30, "material": "g"}],
        "planes": [{"normal": [0, 1, 0], "offset": -3e38, "material": "m"},
                   {"normal": [1e-38, 1, 0], "offset": 3e38, "material": "g"}],
        "lights": [{"position": [3e38, 3e38, -3e38], "radius": 3e38}, {"position": [0, 5, 0]}],
        "render": {"shadow_samples": 4}})");
    expectNoNan(loadScene(json), "extreme.json");
    // A mesh spanning the float range, with a small triangle beside a huge one.
    fs::path huge = writeFile("huge.obj",
                              "v 1e37 1e37 1e37\nv -1e37 -1e37 1e37\nv 1e37 -1e37 -1e37\n"
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 4 5 6\nf 1 2 3\n");
    expectNoNan(loadScene(huge), "huge.obj");
}

// ---- device limits ----
// A device that allows only 4 MiB per buffer (some drivers allow little and do not report a
// failed allocation): the wavefront tiles under it, a row that does not fit is refused with the
// bounce limit that would, and the megakernel's image buffer is refused, all before any buffer
// is created.
TEST(Stability, RayTreeAboveMaxAllocIsTiledOrRefusedBeforeAllocation) {
    DeviceInfo info = test::device().device();
    info.maxAlloc = 4 << 20;
    ClContext small(info);
    Scene scene = loadScene("scenes/spheres.json");  // glass: C = 2
    RenderOptions o = scene.defaults;
    o.width = 64;
    o.height = 48;
    o.bounces = 5;  // 63 nodes and 2 flag words, 194,048 B per row: 21 rows per tile
    WavefrontPipeline tiled(small), whole(test::device());
    Image a = tiled.render(scene, o), b = whole.render(scene, o);
    EXPECT_EQ(tiled.stats().tiles, 3);
    EXPECT_LE(tiled.stats().extras.value("tree_bytes", size_t(0)), info.maxAlloc);
    EXPECT_EQ(std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * 4), 0) << "tiled != whole";

    size_t before = small.allocatedBytes();
    o.width = 4096;
    o.bounces = 10;  // 2,047 nodes: one row is 404 MB
    try {
        tiled.render(scene, o);
        FAIL() << "a 404 MB row rendered under a 4 MiB limit";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("one row of the wavefront ray tree"), std::string::npos) << msg;
        EXPECT_NE(msg.find("max allocation"), std::string::npos) << msg;
        EXPECT_NE(msg.find("the highest bounce limit that fits is 3"), std::string::npos) << msg;
    }
    EXPECT_EQ(small.allocatedBytes(), before) << "nothing new was allocated";

    o.width = o.height = 1024;  // a 12 MiB image buffer
    o.bounces = 1;
    MegakernelPipeline mega(small);
    try {
        mega.render(scene, o);
        FAIL() << "a 12 MiB image buffer was created under a 4 MiB limit";
    } catch (const Error& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("the image buffer"), std::string::npos) << msg;
        EXPECT_NE(msg.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE"), std::string::npos) << msg;
    }
    // At the device's real limit, the widest frame the CLI allows (16384 pixels a row) is tiled
    // under it at every bounce limit whose single row fits, and refused before allocation at
    // every one whose row does not. Which bounce limits fall on which side depends on the
    // device's max allocation (a few GiB on some PoCL builds, tens on a large GPU), so both sides
    // are derived from it rather than assumed.
    const size_t maxAlloc = test::device().device().maxAlloc;
    int fitting = 0;
    for (int bounces = 1; bounces <= 11; ++bounces) {
        const size_t rowBytes = size_t(16384) * WavefrontPipeline::pixelBytes(2, bounces);
        if (rowBytes <= maxAlloc) {
            ++fitting;
            int rows = WavefrontPipeline::tileRows(16384, 16384, 2, bounces, maxAlloc, "max");
            EXPECT_GE(rows, 1) << "B=" << bounces;
            EXPECT_LE(size_t(rows) * rowBytes, maxAlloc) << "B=" << bounces;
        } else {
            EXPECT_THROW(WavefrontPipeline::tileRows(16384, 16384, 2, bounces, maxAlloc, "max"),
                         Error)
                << "B=" << bounces << ": a " << rowBytes << " B row over a " << maxAlloc
                << " B limit";
        }
    }
    EXPECT_GE(fitting, 1) << "OpenCL guarantees at least 128 MiB per allocation: B=1 rows fit";
}

// RTLAB_FAIL_ALLOC_AFTER=n (core/cl_runtime.cpp) fails every allocation that would take the
// context past n bytes, as a driver's clCreateBuffer would fail: the frame ends in one clear
// line, holds nothing it allocated, and the same pipeline renders once allocations work again.
TEST(Stability, AllocationFailureEndsTheFrameWithAClearError) {
    Scene scene = loadScene("scenes/spheres.json");
    RenderOptions o = scene.defaults;
    o.width = 16;
    o.height = 12;
    o.bounces = 2;
    ClContext& cl = test::device();
    for (std::string k : rt::pipelineRegistry().names(true)) {
        size_t before = cl.allocatedBytes();
        std::unique_ptr<Pipeline> p = makePipeline(k, &cl);
        setenv("RTLAB_FAIL_ALLOC_AFTER", std::to_string(before + 1024).c_str(), 1);
        try {
            p->render(scene, o);
            ADD_FAILURE() << k << " rendered with allocations failing";
        } catch (const Error& e) {
            std::string msg = e.what();
            EXPECT_NE(msg.find("CL_MEM_OBJECT_ALLOCATION_FAILURE"), std::string::npos) << msg;
            EXPECT_NE(msg.find("allocating"), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
        unsetenv("RTLAB_FAIL_ALLOC_AFTER");
        EXPECT_EQ(cl.allocatedBytes(), before) << k << ": the failed frame holds bytes";
        Image img = p->render(scene, o);
        EXPECT_EQ(img.width, 16) << k;
    }
}

// A failure while a pipeline resizes its buffers must leave it able to render both sizes. (It did
// not: the wavefront kept its tree size after dropping the tree and traced a null buffer at the
// old size, SIGSEGV on PoCL; the megakernel kept its image size when its second buffer failed.)
TEST(Stability, AllocationFailureOnResizeRecovers) {
    Scene scene = loadScene("scenes/spheres.json");
    RenderOptions o = scene.defaults;
    o.bounces = 2;
    ClContext& cl = test::device();
    auto size = [&](int w, int h) {
        o.width = w;
        o.height = h;
    };
    for (std::string k : {"mega", "wave"}) {
        std::unique_ptr<Pipeline> p = makePipeline(k, &cl);
        // The megakernel keeps a second buffer only for adaptive anti-aliasing's centres.
        o.adaptiveAa = k == "mega";
        o.aa = k == "mega" ? 2 : 1;
        size(32, 24);
        Image first = p->render(scene, o);
        const size_t image = 32 * 24 * 12, smaller = 16 * 12 * 12;
        // Mega: the new image buffer fits, its centre buffer does not. Wave: the tree fails.
        size_t limit =
            k == "mega" ? cl.allocatedBytes() - 2 * image + smaller : cl.allocatedBytes();
        setenv("RTLAB_FAIL_ALLOC_AFTER", std::to_string(limit).c_str(), 1);
        k == "mega" ? size(16, 12) : size(40, 30);
        EXPECT_THROW(p->render(scene, o), Error) << k;
        unsetenv("RTLAB_FAIL_ALLOC_AFTER");
        size(32, 24);
        Image again = p->render(scene, o);
        EXPECT_EQ(std::memcmp(first.rgb.data(), again.rgb.data(), first.rgb.size() * 4), 0)
            << k << ": the old size renders differently after the failure";
        size(16, 12);
        EXPECT_EQ(p->render(scene, o).width, 16) << k;
    }
}

}  // namespace
}  // namespace rt::stress
