// rtlab-stress [--device SPEC] [--out DIR] [--quick] — runs the stress cases (stress.h) on one
// OpenCL device and writes results/<device-slug>/stability.md (sections (a) to (g), stress.cpp):
// each case's figures for the plain and the robust method, and whether the robust one holds its
// bar.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "core/version.h"
#include "pipelines/registry.h"
#include "stress/stress.h"

namespace {

using namespace rt;
using namespace rt::stress;

// The folder name of a device, as rtlab-bench and rtlab sweep write it (bench/measure.cpp).
std::string deviceSlug(const DeviceInfo& d) {
    std::string name = d.name, platform = d.platformName;
    for (char& c : platform) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (platform.find("portable computing language") != std::string::npos ||
        platform.find("pocl") != std::string::npos)
        name = "pocl " + name;
    std::string slug;
    for (unsigned char c : name) {
        if (std::isalnum(c))
            slug += char(std::tolower(c));
        else if (!slug.empty() && slug.back() != '-')
            slug += '-';
    }
    while (!slug.empty() && slug.back() == '-') slug.pop_back();
    return slug.empty() ? "unknown-device" : slug;
}

std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

// "12 / 200,000 (6.0e-05)"
std::string counts(const Counts& c) {
    std::string n = std::to_string(c.rays), grouped;
    for (size_t i = 0; i < n.size(); ++i) {
        if (i && (n.size() - i) % 3 == 0) grouped += ',';
        grouped += n[i];
    }
    return std::to_string(c.bad) + " / " + grouped + " (" + fmt("%.1e", c.rate()) + ")";
}

struct Report {
    std::ostringstream md;
    int failed = 0;
    std::string check(bool ok) {
        if (!ok) ++failed;
        return ok ? "pass" : "**FAIL**";
    }
};

double seconds(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// (g): the scale sweep table and the far tiny sphere.
void scaleSection(ClContext& cl, bool quick, Report& R) {
    std::ostringstream& md = R.md;
    auto t0 = std::chrono::steady_clock::now();
    const std::vector<int> exps = {-4, -3, -2, -1, 1, 2, 3, 4, 5};
    const int w = quick ? 80 : 160, h = quick ? 60 : 120;
    md << "## (g) Scale sweep\n\n"
       << "Each standard scene and its copies scaled by 10^e (positions, radii, plane offsets, "
          "lights and camera; core/scene_scale.h), "
       << w << " x " << h
       << ", bounces <= 4, "
          "shadow samples <= 4: pixels of the scaled render more than 2/255 from the unscaled "
          "one, per offset method (core/SHADING.md section 3: fixed = 1e-4, scaled = 1e-4 "
          "max(1, |p|), bound = past the hit point's rounding-error bound) and pipeline. Bar: "
          "at most 0.1% of the pixels for the bound offset at every scale.\n\n"
       << "| scene | offset | pipeline |";
    for (int e : exps) md << " 1e" << e << " |";
    md << " bar |\n| --- | --- | --- |";
    for (size_t i = 0; i < exps.size(); ++i) md << " --- |";
    md << " --- |\n";
    for (const char* name : {"spheres", "shadows", "cornell", "mesh"}) {
        const std::string path = std::string("scenes/") + name + ".json";
        if (!std::filesystem::exists(path)) {
            md << "| " << name << " | (" << path << " not found: run from the repository root) |\n";
            continue;
        }
        const Scene scene = loadScene(path);
        RenderOptions o = scene.defaults;
        o.width = w;
        o.height = h;
        o.aa = 1;
        o.adaptiveAa = false;
        o.bounces = std::min(o.bounces, 4);
        o.shadowSamples = std::min(o.shadowSamples, 4);
        for (RenderOptions::Offset off : kOffsets)
            for (const std::string& k : pipelineRegistry().names()) {
                o.offset = off;
                std::vector<long long> n = scaleSweep(cl, scene, o, k, exps);
                long long worst = *std::max_element(n.begin(), n.end());
                md << "| " << name << " | " << offsetName(off) << " | " << k << " |";
                for (long long v : n) md << " " << v << " |";
                md << " "
                   << (off == RenderOptions::Offset::Bound ? R.check(worst * 1000 <= w * h)
                                                           : std::string("recorded"))
                   << " |\n";
            }
    }
    md << "\nA sphere of radius r at distance D straight ahead, lit from the camera, 41 x 31: "
          "the centre pixel's largest channel error against the CPU reference. Its float hit "
          "point lies about one ulp of D from the true one. *robust*: Ray Tracing Gems' test, "
          "the normal from its quantities, renormalised (core/SHADING.md section 2); "
          "*--plain-sphere*: the report's test and normal, for comparison (the quadratic "
          "misses such spheres). Bar: within 1/255 for the robust sphere at D = 1e4.\n\n"
       << "| D | r | pipeline | --plain-sphere | robust | bar |\n| --- | --- | --- | --- | --- | "
          "--- |\n";
    for (double D : {1e2, 1e3, 1e4})
        for (const std::string& k : pipelineRegistry().names(true)) {
            double plain = farSphereCentreError(cl, k, false, D, 1e-3);
            double robust = farSphereCentreError(cl, k, true, D, 1e-3);
            md << "| " << fmt("%g", D) << " | 0.001 | " << k << " | "
               << fmt("%.2f/255", plain * 255) << " | " << fmt("%.2f/255", robust * 255) << " | "
               << (D == 1e4 ? R.check(robust <= 1.0 / 255) : std::string("recorded")) << " |\n";
        }
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n";
}

void runAll(ClContext& cl, bool quick, Report& R) {
    std::ostringstream& md = R.md;
    const int scaleDown = quick ? 10 : 1;
    auto t0 = std::chrono::steady_clock::now();

    md << "## (a) Leaks through shared edges and vertices of a closed mesh\n\n"
       << "Embree's watertightness test: a UV sphere of radius 2 (64 x 128 segments, 16,128 "
          "triangles, every vertex rounded to float once), rays from random points of the cube "
          "[-1, 1]^3 around its centre in random directions, plus one ray at the float midpoint "
          "of each triangle edge (each shared edge twice) and one at each vertex. A miss is a "
          "leak. Whole closest-hit query through the BVH (`Probe_Closest`). Bar (Embree): miss "
          "rate <= 2e-5 for the watertight test.\n\n"
       << "| centre | test | random rays | edge midpoints | vertices | bar |\n"
       << "| --- | --- | --- | --- | --- | --- |\n";
    for (dvec3 c : {dvec3(0, 0, 0), dvec3(148376, 1234, -223423)})
        for (bool wt : {false, true}) {
            LeakResult r = leaks(cl, wt, c, 200000 / scaleDown);
            Counts all = r.random;
            all += r.edges;
            all += r.vertices;
            md << "| (" << c.x << ", " << c.y << ", " << c.z << ") | "
               << (wt ? "watertight" : "Moller-Trumbore") << " | " << counts(r.random) << " | "
               << counts(r.edges) << " | " << counts(r.vertices) << " | "
               << (wt ? R.check(r.random.rate() <= 2e-5) : std::string("recorded")) << " |\n";
        }
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n\n";

    t0 = std::chrono::steady_clock::now();
    md << "## (b) Tiny spheres far from the origin\n\n"
       << "Spheres of radius r at distance D from the camera in random directions. Half the "
          "rays aim within 0.9 r of the centre (a miss is an error), half 1.1 r to 2 r off it (a "
          "hit is an error). `Probe_Sphere`, plain = report Algorithm 2, robust = Ray Tracing "
          "Gems ch. 7. Bar: no error for the robust test at D = 1e3, r = 1e-2 (r/D = 1e-5).\n\n"
       << "| D | r | r/D | plain: misses | plain: false hits | robust: misses | robust: false "
          "hits |\n| --- | --- | --- | --- | --- | --- | --- |\n";
    for (double D : {1e2, 1e3, 1e4})
        for (double r : {1.0, 1e-1, 1e-2, 1e-3}) {
            SphereResult p = tinySpheres(cl, false, D, r, 20000 / scaleDown);
            SphereResult q = tinySpheres(cl, true, D, r, 20000 / scaleDown);
            bool barCase = D == 1e3 && r == 1e-2;
            md << "| " << fmt("%g", D) << " | " << fmt("%g", r) << " | " << fmt("%.0e", r / D)
               << " | " << counts(p.misses) << " | " << counts(p.falseHits) << " | "
               << counts(q.misses) << " | " << counts(q.falseHits)
               << (barCase ? " " + R.check(q.misses.bad == 0 && q.falseHits.bad == 0) : "")
               << " |\n";
        }
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n\n";

    t0 = std::chrono::steady_clock::now();
    md << "## (c) Self-intersection of secondary rays (shadow acne) at every scale\n\n"
       << "A triangulated sphere (24 x 48) and an analytic sphere of radius s at distance 4 s "
          "from the camera at the origin; from each of 2,000 primary hits, 64 random rays leave "
          "as the pipelines spawn them (`Probe_Spawn`: hit point and origins from "
          "`RayTree_TraceNode` and `RayTree_SpawnOrigin`). *out*: reflection/shadow side, a hit on "
          "the same object is acne; "
          "*in*: refraction side, a hit on the same triangle (or on the sphere within 1e-3 r) is "
          "acne; *escaped*: refraction rays that never hit the object they start in, because "
          "the offset pushed the origin through it. fixed = 1e-4, scaled = 1e-4 max(1, |p|), "
          "bound = just past the hit point's rounding-error bound (core/SHADING.md section 3). "
          "Bar: 0 acne and 0 escapes for the scaled offset at s = 1e-3 and s = 1e5, and for "
          "the bound offset at every scale.\n\n"
       << "| s | offset | mesh out | mesh in | mesh escaped | sphere out | sphere in | sphere "
          "escaped | bar |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (double s : {1e-8, 1e-5, 1e-3, 1.0, 1e3, 1e5, 1e8})
        for (RenderOptions::Offset off : kOffsets) {
            AcneResult a = acne(cl, s, off, 2000 / scaleDown, 64);
            bool barCase = off == RenderOptions::Offset::Bound ||
                           (off == RenderOptions::Offset::Scaled && (s == 1e-3 || s == 1e5));
            long long bad = a.meshOut.bad + a.meshIn.bad + a.meshEscape.bad + a.sphereOut.bad +
                            a.sphereIn.bad + a.sphereEscape.bad;
            md << "| " << fmt("%g", s) << " | " << offsetName(off) << " | " << counts(a.meshOut)
               << " | " << counts(a.meshIn) << " | " << counts(a.meshEscape) << " | "
               << counts(a.sphereOut) << " | " << counts(a.sphereIn) << " | "
               << counts(a.sphereEscape) << " | "
               << (barCase ? R.check(bad == 0) : std::string("recorded")) << " |\n";
        }
    md << "\npbrt-v4's `Triangle.Reintersect` (`Probe_Reintersect`): 1,000 lone triangles, a ray "
          "from a random origin to a random point of each (hit point as the pipelines compute "
          "it: o + t d, or from the barycentrics for the bound offset), then 1,000 random "
          "directions leave it with the offset on the side they "
          "point to. *mixed*: every coordinate of vertices and origin is 10^U(-8, 8) on its own, "
          "as in pbrt; *scale s*: coordinates in [-1, 1] s, origin in [-4, 4] s. pbrt's bar: 0 "
          "re-hits; pbrt meets it at mixed scales only because its triangle test also rejects "
          "t below a bound on t's own error, which ours does not (so mixed is recorded).\n\n"
       << "| triangles | offset | first ray missed | triangles with re-hits | re-hits / rays |\n"
       << "| --- | --- | --- | --- | --- |\n";
    auto reRow = [&](const std::string& label, bool mixed, double lo, double hi) {
        for (RenderOptions::Offset off : kOffsets) {
            ReintersectResult r = reintersect(cl, off, lo, hi, mixed, 1000 / scaleDown, 1000);
            md << "| " << label << " | " << offsetName(off) << " | " << r.missed << " | "
               << r.withRehits << " | " << counts(r.rehits) << " |\n";
        }
    };
    reRow("mixed 1e-8..1e8", true, -8, 8);
    for (double e : {-8.0, -5.0, -3.0, 0.0, 3.0, 5.0, 8.0})
        reRow("scale " + fmt("%g", std::pow(10.0, e)), false, e, e);
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n\n";

    t0 = std::chrono::steady_clock::now();
    CriticalResult c = criticalAngle(cl);
    md << "## (d) Grazing rays and the critical angle\n\n"
       << "Rays leaving a medium of index 1.0001, 1.1, 1.333, 1.5, 1.7, 2.42 and 4 at its "
          "critical angle and at 256 angles 1e-7 rad apart on each side, through "
          "`Shade_Refract` and `Shade_Fresnel` (`Probe_Refract`). Bar: no non-finite output, "
          "F in [0, 1], F = 1 whenever no refracted ray is made, refracted rays of unit "
          "length.\n\n"
       << "| cases | total internal reflection (device) | non-finite | inconsistent F | "
          "non-unit | TIR decision differs from double | bar |\n"
       << "| --- | --- | --- | --- | --- | --- | --- |\n"
       << "| " << c.cases << " | " << c.tirDevice << " | " << c.nonFinite << " | " << c.inconsistent
       << " | " << c.nonUnit << " | " << c.disagree << " | "
       << R.check(c.nonFinite == 0 && c.inconsistent == 0 && c.nonUnit == 0) << " |\n\n"
       << "Grazing rays (`Probe_TriangleHits`): 512 rays per elevation angle, aimed at interior "
          "points (5% clear of the edges) of a triangle in the plane y = 0 from 10 units away; "
          "angle 0 means exactly in the plane (a hit is the error there), otherwise a miss "
          "is.\n\n| elevation | Moller-Trumbore | watertight |\n| --- | --- | --- |\n";
    std::vector<Counts> mt = grazing(cl, false), wt = grazing(cl, true);
    for (int k = 0; k <= 7; ++k)
        md << "| " << (k ? "1e-" + std::to_string(k) : std::string("0 (in the plane)")) << " | "
           << counts(mt[k]) << " | " << counts(wt[k]) << " |\n";
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n\n";

    t0 = std::chrono::steady_clock::now();
    md << "## (e) Nested dielectrics\n\n"
       << "A glass sphere (ior 1.5, opacity 0.1) inside a glass sphere (ior 1.33), a mirror and "
          "a diffuse sphere on a plane, 64 x 48, against the double-precision CPU reference. "
          "Bar: every pixel finite, >= 99% within 2/255.\n\n"
       << "| pipeline | bounces | non-finite pixels | within 2/255 | mean abs error | max abs "
          "error | bar |\n| --- | --- | --- | --- | --- | --- | --- |\n";
    for (const std::string& k : pipelineRegistry().names(true))
        for (int b : {2, 6}) {
            NestedResult n = nested(cl, k, 64, 48, b);
            double within = double(n.within) / double(n.pixels);
            md << "| " << k << " | " << b << " | " << n.nonFinite << " | "
               << fmt("%.2f%%", 100 * within) << " | " << fmt("%.3f/255", n.meanAbs * 255) << " | "
               << fmt("%.2f/255", n.maxAbs * 255) << " | "
               << R.check(n.nonFinite == 0 && within >= 0.99) << " |\n";
        }
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n\n";

    t0 = std::chrono::steady_clock::now();
    md << "## (f) NaN and Inf rays\n\n"
       << "252 rays whose origin, direction or both hold NaN, +Inf or -Inf in one to three "
          "components, against spheres, a plane and a closed mesh (Embree's NaN/Inf tests). "
          "*bad hits*: a reported hit with a non-finite or non-positive t or an object out of "
          "range. *non-finite colours*: whole ray trees (`Probe_Shade`, 2 bounces) whose colour "
          "is not finite. Bar: it returns (no crash, no hang) and reports no bad hit; the "
          "colours are recorded (camera rays of a loaded scene are always finite: the loader "
          "rejects non-finite cameras and geometry).\n\n"
       << "| accel | rays | bad hits | non-finite colours | bar |\n| --- | --- | --- | --- | --- "
          "|\n";
    for (RenderOptions::Accel a : {RenderOptions::Accel::None, RenderOptions::Accel::Bv,
                                   RenderOptions::Accel::Grid, RenderOptions::Accel::Bvh}) {
        NanResult n = nanRays(cl, a);
        md << "| " << accelName(a) << " | " << n.rays << " | " << n.badHits << " | " << n.nanPixels
           << " | " << R.check(n.badHits == 0) << " |\n";
    }
    md << "\n(" << fmt("%.1f", seconds(t0)) << " s)\n\n";
    scaleSection(cl, quick, R);
}

}  // namespace

int main(int argc, char** argv) {
    std::string deviceSpec, out;
    bool quick = false;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if ((a == "--device" || a == "--out") && i + 1 < argc) {
            (a == "--device" ? deviceSpec : out) = argv[++i];
        } else if (a == "--quick") {
            quick = true;
        } else {
            std::fprintf(stderr,
                         "usage: rtlab-stress [--device INDEX|NAME|cpu|gpu] [--out DIR] [--quick]\n"
                         "  Runs the numerical stress suite on one OpenCL device and "
                         "writes DIR/stability.md\n  (default DIR: results/<device-slug>). "
                         "--quick: a tenth of the rays. Exit 2 when a bar fails.\n");
            return a == "--help" || a == "-h" ? 0 : 1;
        }
    }
    try {
        ClContext cl(selectDevice(deviceSpec));
        const DeviceInfo& d = cl.device();
        if (out.empty()) out = "results/" + deviceSlug(d);
        std::fprintf(stderr, "rtlab-stress: %s\n", d.label().c_str());
        auto t0 = std::chrono::steady_clock::now();
        Report R;
        runAll(cl, quick, R);
        std::time_t now = std::time(nullptr);
        char date[32];
        std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
        std::filesystem::create_directories(out);
        std::ofstream f(std::filesystem::path(out) / "stability.md");
        f << "# Numerical stress suite: " << d.name << "\n\n"
          << "Written by `rtlab-stress" << (quick ? " --quick" : "") << "` (stress/) on "
          << d.label() << ", commit " << RTLAB_COMMIT << ", " << date << ", in "
          << fmt("%.0f", seconds(t0)) << " s. Counts are *errors / cases (rate)*. "
          << "Each case asserts the robust method's figure (column *bar*; the same checks run "
          << "in tests/stability_test.cpp) and records the plain one's.\n\n"
          << (R.failed ? std::to_string(R.failed) + " bar(s) FAILED.\n\n" : "Every bar holds.\n\n")
          << R.md.str();
        if (!f) throw Error(out + "/stability.md: cannot write");
        std::printf("rtlab-stress: wrote %s/stability.md (%s)\n", out.c_str(),
                    R.failed ? "some bars FAILED" : "every bar holds");
        return R.failed ? 2 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab-stress: %s\n", e.what());
        return 1;
    }
}
