// rtlab-stress — the numerical stress suite, run through the device code of both
// pipelines (probe kernels at the end of core/cl/probe.cl) on any OpenCL device, and written as
// results/<device-slug>/stability.md (stress_main.cpp). The cases are a library (stress.h) that
// rtlab-stress and tests/stability_test.cpp both link, so the tool and the test cannot drift
// apart; it needs no OpenImageIO, so rtlab-stress can be carried to a GPU machine.
//
// Each case counts a failure of the plain method (the report's algorithm) and of the robust one:
//   (a) leaks through shared edges and vertices of a closed mesh: Moller-Trumbore vs watertight,
//       Embree's test (a triangulated sphere far from the origin, rays from inside, <= 2e-5);
//   (b) tiny spheres far away: misses of the plain quadratic vs Ray Tracing Gems ch. 7;
//   (c) self-intersection of secondary rays at scales 1e-8..1e8: fixed epsilon vs scaled offset,
//       over a scene and pbrt-v4's Triangle.Reintersect (lone triangles, coordinates 1e-8..1e8);
//   (d) grazing rays and refraction at exactly the critical angle;
//   (e) nested dielectrics against the CPU reference;
//   (f) NaN and Inf rays through every acceleration structure;
//   (g) scale sweep: pixels that change when a standard scene is scaled by 1e-4..1e5, per offset
//       method and pipeline, and a sphere of radius 1e-3 at distance 1e4.
#include "stress/stress.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <glm/glm.hpp>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "core/scene_scale.h"
#include "pipelines/registry.h"

namespace rt::stress {

using glm::dvec3;

// ---- scenes built by hand ----
dev::Float3 f3(dvec3 v) { return {float(v.x), float(v.y), float(v.z)}; }

dev::Material material(float opacity, float ior, float reflectance) {
    dev::Material m{};
    m.ambient = {0.05f, 0.05f, 0.05f};
    m.diffuse = {0.6f, 0.6f, 0.6f};
    m.specular = {0.3f, 0.3f, 0.3f};
    m.exponent = 32.f;
    m.reflectance = reflectance;
    m.opacity = opacity;
    m.ior = ior;
    return m;
}

Scene emptyScene(const char* name) {
    Scene s;
    s.name = name;
    s.materials = {material()};
    s.materialNames = {"grey"};
    s.camera = {{0, 0, 0}, 0.f, 0.f, 0.785398f, {0, 0}};
    return s;
}

// A closed UV sphere: every vertex is rounded to float once and shared by all its triangles, as
// in an indexed mesh, so the surface has no cracks in float arithmetic. Returns its vertices.
std::vector<dev::Float3> addMeshSphere(Scene& s, dvec3 c, double r, int rings, int segments) {
    std::vector<dev::Float3> v, n;
    auto add = [&](double theta, double phi) {
        dvec3 d(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
        v.push_back(f3(c + r * d));
        n.push_back(f3(d));
    };
    add(0, 0);  // north pole, index 0
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) add(M_PI * i / rings, 2 * M_PI * j / segments);
    add(M_PI, 0);  // south pole, last
    const int south = int(v.size()) - 1;
    auto at = [&](int i, int j) { return 1 + (i - 1) * segments + j % segments; };
    const int first = int(s.triangles.size());
    auto tri = [&](int a, int b, int c2) {
        s.triangles.push_back({v[a], v[b], v[c2], n[a], n[b], n[c2], 0, 0});
    };
    for (int j = 0; j < segments; ++j) {
        tri(0, at(1, j + 1), at(1, j));
        for (int i = 1; i + 1 < rings; ++i) {
            tri(at(i, j), at(i, j + 1), at(i + 1, j + 1));
            tri(at(i, j), at(i + 1, j + 1), at(i + 1, j));
        }
        tri(south, at(rings - 1, j), at(rings - 1, j + 1));
    }
    s.meshes.push_back({first, int(s.triangles.size()) - first, -1, 0, {}, {}, {}, 0.f, {}});
    return v;
}

// ---- running probe kernels ----
template <typename T>
cl::Buffer input(ClContext& cl, const std::vector<T>& v) {
    return cl::Buffer(cl.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                      std::max<size_t>(v.size() * sizeof(T), 16), const_cast<T*>(v.data()));
}

template <typename T>
std::vector<T> output(ClContext& cl, const cl::Buffer& b, size_t n) {
    std::vector<T> v(n);
    cl.queue().enqueueReadBuffer(b, CL_TRUE, 0, n * sizeof(T), v.data());
    return v;
}

// The probe program for a scene: its feature defines and the size of a whole ray tree, which
// Probe_Shade keeps in private memory.
std::vector<std::string> probeDefines(const Scene& scene, const RenderOptions& o) {
    std::vector<std::string> d = featureDefines(scene, o);
    d.push_back(treeNodesDefine(scene, o.bounces));
    return d;
}

// A probe kernel bound to a scene's device copy; its own arguments are set by name.
struct SceneProbe {
    SceneProbe(ClContext& cl, const Scene& scene, const RenderOptions& o, const char* kernel)
        : device(cl, scene, o.accel),
          program(cl.program("probe.cl", probeDefines(scene, o))),
          k(program, kernel) {
        device.setArgs(k, makeSettings(scene, o));
    }
    void run(ClContext& cl, size_t n) {
        cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(n), cl::NullRange);
        cl.queue().finish();
    }
    DeviceScene device;
    cl::Program program;
    Kernel k;
};

// Closest hits of rays (6 floats each): t (-1 on a miss) and (kind, object).
void closest(ClContext& cl, const Scene& scene, const RenderOptions& o,
             const std::vector<float>& rays, std::vector<float>* t, std::vector<cl_int2>* what) {
    size_t n = rays.size() / 6;
    SceneProbe p(cl, scene, o, "Probe_Closest");
    cl::Buffer in = input(cl, rays);
    cl::Buffer tb(cl.context(), CL_MEM_WRITE_ONLY, n * 4),
        wb(cl.context(), CL_MEM_WRITE_ONLY, n * 8);
    p.k.set("rays", in).set("t", tb).set("what", wb);
    p.run(cl, n);
    *t = output<float>(cl, tb, n);
    if (what) *what = output<cl_int2>(cl, wb, n);
}

void pushRay(std::vector<float>& rays, dvec3 o, dvec3 d) {
    dev::Float3 of = f3(o), df = f3(glm::normalize(d));
    rays.insert(rays.end(), {of.x, of.y, of.z, df.x, df.y, df.z});
}

dvec3 d3(const dev::Float3& f) { return {f.x, f.y, f.z}; }

dvec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    dvec3 v(g(rng), g(rng), g(rng));
    return glm::normalize(v);
}

// ---- (a) leaks through a closed mesh ----

// Embree's watertightness test: a sphere of radius 2 centred at `center`, rays from points of
// the cube [-1, 1]^3 around the centre in random directions; also rays aimed exactly at edge
// midpoints and at vertices, where a leak is most likely. Misses are leaks.
LeakResult leaks(ClContext& cl, bool watertight, dvec3 center, int randomRays, int rings) {
    Scene scene = emptyScene("leaks");
    std::vector<dev::Float3> verts = addMeshSphere(scene, center, 2.0, rings, 2 * rings);
    finalizeScene(scene);
    RenderOptions o;
    o.watertight = watertight;
    o.accel = RenderOptions::Accel::Bvh;
    o.bounces = 0;
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-1, 1);
    auto origin = [&] { return center + dvec3(u(rng), u(rng), u(rng)); };
    std::vector<float> rays;
    for (int i = 0; i < randomRays; ++i) pushRay(rays, origin(), randomUnit(rng));
    size_t edgeStart = rays.size() / 6;
    for (const dev::Triangle& t : scene.triangles) {
        const dev::Float3* v[3] = {&t.v0, &t.v1, &t.v2};
        for (int k = 0; k < 3; ++k) {  // each edge is shared by two triangles: aimed at twice
            dev::Float3 mid = {(v[k]->x + v[(k + 1) % 3]->x) * 0.5f,
                               (v[k]->y + v[(k + 1) % 3]->y) * 0.5f,
                               (v[k]->z + v[(k + 1) % 3]->z) * 0.5f};
            dvec3 o2 = origin();
            pushRay(rays, o2, d3(mid) - o2);
        }
    }
    size_t vertexStart = rays.size() / 6;
    for (const dev::Float3& v : verts) {
        dvec3 o2 = origin();
        pushRay(rays, o2, d3(v) - o2);
    }
    std::vector<float> t;
    closest(cl, scene, o, rays, &t, nullptr);
    LeakResult r;
    for (size_t i = 0; i < t.size(); ++i) {
        Counts& c = i < edgeStart ? r.random : i < vertexStart ? r.edges : r.vertices;
        ++c.rays;
        if (!(t[i] > 0.f)) ++c.bad;
    }
    return r;
}

// ---- (b) tiny spheres far away ----

// Spheres of radius r at distance D from the camera (the world origin), in random directions.
SphereResult tinySpheres(ClContext& cl, bool robust, double distance, double radius, int rays) {
    std::vector<std::string> defines;
    if (robust) defines.push_back("RT_ROBUST_SPHERE");
    cl::Program program = cl.program("probe.cl", defines);
    std::mt19937 rng(uint32_t(distance * 7 + radius * 1e6));
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<float> in;
    for (int i = 0; i < rays; ++i) {
        dvec3 dir = randomUnit(rng), c = distance * dir;
        dvec3 side = glm::normalize(glm::cross(dir, randomUnit(rng)));
        bool inside = i % 2 == 0;
        double off = radius * (inside ? 0.9 * std::sqrt(u(rng)) : 1.1 + 0.9 * u(rng));
        dev::Float3 cf = f3(c), df = f3(glm::normalize(c + off * side));
        in.insert(in.end(), {0.f, 0.f, 0.f, df.x, df.y, df.z, cf.x, cf.y, cf.z, float(radius)});
    }
    Kernel k(program, "Probe_Sphere");
    cl::Buffer ib = input(cl, in), tb(cl.context(), CL_MEM_WRITE_ONLY, rays * 4);
    k.set("in", ib).set("t", tb);
    cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(rays), cl::NullRange);
    std::vector<float> t = output<float>(cl, tb, rays);
    SphereResult r;
    for (int i = 0; i < rays; ++i) {
        bool hit = t[i] > 0.f;
        Counts& c = i % 2 == 0 ? r.misses : r.falseHits;
        ++c.rays;
        if (hit != (i % 2 == 0)) ++c.bad;
    }
    return r;
}

// ---- (c) self-intersection of secondary rays ----

// A triangulated sphere and an analytic one, radius `scale`, at 4 * scale in front of the
// camera at the origin. From every primary hit, `spawn` rays leave outward (reflection and
// shadow rays: a hit on the same object is acne) and inward (refraction rays: a hit on the same
// triangle, or the sphere right at the start, is acne; leaving without hitting it means the
// offset pushed the origin through the object).
AcneResult acne(ClContext& cl, double scale, RenderOptions::Offset offset, int primary, int spawn) {
    Scene scene = emptyScene("acne");
    const dvec3 meshC = scale * dvec3(-1.2, 0.1, 4), sphereC = scale * dvec3(1.2, -0.1, 4);
    addMeshSphere(scene, meshC, scale, 24, 48);
    scene.spheres.push_back({f3(sphereC), float(scale), 0, {0, 0, 0}});
    finalizeScene(scene);
    RenderOptions o;
    o.offset = offset;
    o.accel = RenderOptions::Accel::Bvh;
    o.bounces = 1;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.95, 0.95);
    std::vector<float> rays;
    for (int i = 0; i < primary; ++i) {
        dvec3 c = i % 2 ? sphereC : meshC, p;
        do p = dvec3(u(rng), u(rng), 0);
        while (glm::length(p) > 0.95);
        pushRay(rays, dvec3(0), c + scale * p);
    }
    SceneProbe probe(cl, scene, o, "Probe_Spawn");
    cl::Buffer in = input(cl, rays), out(cl.context(), CL_MEM_WRITE_ONLY, primary * 8 * 4);
    probe.k.set("rays", in).set("spawn", cl_int(spawn)).set("out", out);
    probe.run(cl, primary);
    std::vector<cl_int> c = output<cl_int>(cl, out, size_t(primary) * 8);
    AcneResult r;
    for (int i = 0; i < primary; ++i) {
        const cl_int* e = &c[size_t(i) * 8];
        bool mesh = e[0] == RT_KIND_TRIANGLE;
        if (e[0] != RT_KIND_TRIANGLE && e[0] != RT_KIND_SPHERE) continue;
        (mesh ? r.meshOut : r.sphereOut) += Counts{e[1], e[2]};
        (mesh ? r.meshIn : r.sphereIn) += Counts{e[3], e[4]};
        (mesh ? r.meshEscape : r.sphereEscape) += Counts{e[3], e[5]};
    }
    return r;
}

// pbrt-v4's Triangle.Reintersect: lone triangles whose coordinates are each 10^U(lo, hi)
// (mixed: every coordinate its own exponent, as pbrt; else one scale 10^lo for the whole
// triangle, coordinates in [-1, 1] times it), hit by a ray from an origin drawn the same way,
// then `spawn` rays leave the hit point. Re-hits of the same triangle are counted.

ReintersectResult reintersect(ClContext& cl, RenderOptions::Offset offset, double lo, double hi,
                              bool mixed, int triangles, int spawn) {
    Scene scene = emptyScene("reintersect");  // only for the program's defines
    addMeshSphere(scene, dvec3(0, 0, 4), 1, 4, 8);
    RenderOptions o;
    o.offset = offset;
    cl::Program program = cl.program("probe.cl", probeDefines(scene, o));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> e(lo, hi), s(-1, 1), u(0, 1);
    auto coord = [&] { return mixed ? std::pow(10.0, e(rng)) : s(rng) * std::pow(10.0, lo); };
    std::vector<float> tris, origins, targets;
    for (int i = 0; i < triangles; ++i) {
        dvec3 v[3];
        for (dvec3& p : v) p = dvec3(coord(), coord(), coord());
        dvec3 org =
            mixed ? dvec3(coord(), coord(), coord()) : 4.0 * dvec3(coord(), coord(), coord());
        double a = u(rng), b = u(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        dvec3 target = (1 - a - b) * v[0] + a * v[1] + b * v[2];
        for (dvec3& p : v) tris.insert(tris.end(), {float(p.x), float(p.y), float(p.z)});
        origins.insert(origins.end(), {float(org.x), float(org.y), float(org.z)});
        targets.insert(targets.end(), {float(target.x), float(target.y), float(target.z)});
    }
    Kernel k(program, "Probe_Reintersect");
    cl::Buffer tb = input(cl, tris), ob = input(cl, origins), gb = input(cl, targets);
    cl::Buffer out(cl.context(), CL_MEM_WRITE_ONLY, triangles * 4);
    k.set("tris", tb)
        .set("origins", ob)
        .set("targets", gb)
        .set("spawn", cl_int(spawn))
        .set("out", out);
    cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(triangles), cl::NullRange);
    std::vector<cl_int> hits = output<cl_int>(cl, out, triangles);
    ReintersectResult r;
    r.triangles = triangles;
    for (cl_int h : hits) {
        if (h < 0) {
            ++r.missed;
            continue;
        }
        r.rehits += Counts{spawn, h};
        if (h > 0) ++r.withRehits;
    }
    return r;
}

// ---- (d) grazing rays and the critical angle ----

// Rays inside a medium of index ior toward air at the critical angle asin(1/ior) (as float,
// and 256 neighbouring angles 1e-7 rad apart on each side), through Shade_Refract and
// Shade_Fresnel. Inconsistent: no refracted ray but F < 1 (energy lost), or F outside [0, 1].
// disagree: the float decision on total internal reflection differs from the double reference.
CriticalResult criticalAngle(ClContext& cl) {
    Scene scene = emptyScene("critical");
    scene.spheres.push_back({{0, 0, 4}, 1.f, 0, {0, 0, 0}});
    RenderOptions o;
    cl::Program program = cl.program("probe.cl", probeDefines(scene, o));
    std::vector<float> in;
    std::vector<double> iors = {1.0001, 1.1, 1.333, 1.5, 1.7, 2.42, 4.0};
    for (double ior : iors)
        for (int k = -256; k <= 256; ++k) {
            double theta = std::asin(1.0 / ior) + k * 1e-7;
            dev::Float3 d = f3(dvec3(std::sin(theta), -std::cos(theta), 0));
            in.insert(in.end(), {d.x, d.y, d.z, 0.f, 1.f, 0.f, float(ior), float(ior), 1.f});
        }
    size_t n = in.size() / 9;
    Kernel k(program, "Probe_Refract");
    cl::Buffer ib = input(cl, in), ob(cl.context(), CL_MEM_WRITE_ONLY, n * 5 * 4);
    k.set("in", ib).set("out", ob);
    cl.queue().enqueueNDRangeKernel(k.get(), cl::NullRange, cl::NDRange(n), cl::NullRange);
    std::vector<float> out = output<float>(cl, ob, n * 5);
    CriticalResult r;
    for (size_t i = 0; i < n; ++i) {
        const float* a = &in[i * 9];
        const float* b = &out[i * 5];
        ++r.cases;
        bool ok = b[0] != 0.f;
        float F = b[4];
        if (!ok) ++r.tirDevice;
        if (!std::isfinite(F) || !std::isfinite(b[1]) || !std::isfinite(b[2]) ||
            !std::isfinite(b[3]))
            ++r.nonFinite;
        if (!(F >= 0.f && F <= 1.f) || (!ok && F != 1.f)) ++r.inconsistent;
        if (ok && std::abs(std::sqrt(b[1] * b[1] + b[2] * b[2] + b[3] * b[3]) - 1.f) > 1e-4f)
            ++r.nonUnit;
        dvec3 d(a[0], a[1], a[2]);
        bool refOk = ref::refract(glm::normalize(d), dvec3(0, 1, 0), a[6]).has_value();
        if (refOk != ok) ++r.disagree;
    }
    return r;
}

// Rays at angles 10^-k (k = 1..7) and exactly 0 to a unit triangle in the plane y = 0, aimed at
// interior points from 10 units away. Index k holds angle 10^-k; index 0 the coplanar rays
// (which must miss); bad = misses for k >= 1, hits for k = 0.
std::vector<Counts> grazing(ClContext& cl, bool watertight, int perAngle) {
    std::vector<std::string> defines = {"RT_HAS_TRIANGLES"};
    if (watertight) defines.push_back("RT_WATERTIGHT");
    cl::Program program = cl.program("probe.cl", defines);
    std::vector<float> tri = {-1, 0, -1, 1, 0, -1, 0, 0, 1.2f};
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, 1), ang(0, 2 * M_PI);
    std::vector<float> rays;
    for (int k = 0; k <= 7; ++k)
        for (int i = 0; i < perAngle; ++i) {
            double a = u(rng), b = u(rng);
            if (a + b > 1) a = 1 - a, b = 1 - b;
            a = 0.05 + 0.9 * a, b = 0.05 + 0.9 * b * (1 - a);  // keep clear of the edges
            dvec3 p = (1 - a - b) * dvec3(-1, 0, -1) + a * dvec3(1, 0, -1) + b * dvec3(0, 0, 1.2);
            double elev = k == 0 ? 0.0 : std::pow(10.0, -k), phi = ang(rng);
            dvec3 d(std::cos(elev) * std::cos(phi), -std::sin(elev),
                    std::cos(elev) * std::sin(phi));
            dvec3 o = p - 10.0 * d;
            if (k == 0) o.y = 0;  // exactly in the plane
            dev::Float3 of = f3(o), df = f3(d);
            if (k == 0) df.y = 0.f;
            rays.insert(rays.end(), {of.x, of.y, of.z, df.x, df.y, df.z});
        }
    size_t n = rays.size() / 6;
    Kernel kern(program, "Probe_TriangleHits");
    cl::Buffer rb = input(cl, rays), tb = input(cl, tri),
               hb(cl.context(), CL_MEM_WRITE_ONLY, n * 4);
    kern.set("rays", rb).set("tris", tb).set("count", cl_int(1)).set("hits", hb);
    cl.queue().enqueueNDRangeKernel(kern.get(), cl::NullRange, cl::NDRange(n), cl::NullRange);
    std::vector<cl_int> hits = output<cl_int>(cl, hb, n);
    std::vector<Counts> r(8);
    for (size_t i = 0; i < n; ++i) {
        int k = int(i / perAngle);
        ++r[k].rays;
        if ((hits[i] > 0) != (k > 0)) ++r[k].bad;
    }
    return r;
}

// ---- (e) nested dielectrics ----

// A glass sphere (ior 1.5) inside a glass sphere (ior 1.33) over a checker of diffuse spheres
// on a plane; transparent, so C = 2.
Scene nestedScene() {
    Scene s = emptyScene("nested");
    s.materials = {material(), material(0.1f, 1.33f), material(0.1f, 1.5f), material(1, 1, 0.5f)};
    s.materialNames = {"grey", "outer", "inner", "mirror"};
    s.materials[0].diffuse = {0.8f, 0.3f, 0.2f};
    s.spheres.push_back({{0, 1.2f, 6}, 1.2f, 1, {0, 0, 0}});
    s.spheres.push_back({{0, 1.2f, 6}, 0.6f, 2, {0, 0, 0}});
    s.spheres.push_back({{1.8f, 0.5f, 8}, 0.5f, 3, {0, 0, 0}});
    s.spheres.push_back({{-1.8f, 0.5f, 8}, 0.5f, 0, {0, 0, 0}});
    s.planes.push_back({{0, 1, 0}, 0.f, 0, {0, 0, 0}});
    s.lights.push_back({{2, 6, 2}, 0.f, {1, 1, 1}, 0.f});
    s.camera = {{0, 1.2f, 0}, 0.f, 0.f, 0.7f, {0, 0}};
    finalizeScene(s);
    return s;
}

NestedResult compare(const Image& a, const Image& b) {
    NestedResult r;
    r.pixels = a.width * a.height;
    double sum = 0;
    for (size_t p = 0; p < a.rgb.size() / 3; ++p) {
        double worst = 0;
        bool finite = true;
        for (int c = 0; c < 3; ++c) {
            float x = a.rgb[p * 3 + c], y = b.rgb[p * 3 + c];
            finite = finite && std::isfinite(x);
            double e = std::abs(std::clamp(double(x), 0.0, 1.0) - std::clamp(double(y), 0.0, 1.0));
            worst = std::max(worst, std::isfinite(x) ? e : 1.0);
            sum += std::isfinite(x) ? e : 1.0;
        }
        if (!finite) ++r.nonFinite;
        if (worst <= 2.0 / 255.0) ++r.within;
        r.maxAbs = std::max(r.maxAbs, worst);
    }
    r.meanAbs = sum / double(a.rgb.size());
    return r;
}

NestedResult nested(ClContext& cl, const std::string& kind, int width, int height, int bounces) {
    Scene scene = nestedScene();
    RenderOptions o;
    o.width = width;
    o.height = height;
    o.bounces = bounces;
    std::unique_ptr<Pipeline> p = makePipeline(kind, &cl);
    return compare(p->render(scene, o), renderReference(scene, o));
}

// ---- (f) NaN and Inf rays ----

// Spheres, a plane and a closed mesh; rays whose origin, direction or both hold NaN, +Inf or
// -Inf in one or all components. badHits: a reported hit with a non-finite or negative t or an
// object index out of range. nanPixels: whole ray trees (Probe_Shade) whose colour is not finite.
NanResult nanRays(ClContext& cl, RenderOptions::Accel accel) {
    Scene scene = emptyScene("nan");
    addMeshSphere(scene, dvec3(0, 1, 6), 1, 8, 16);
    scene.spheres.push_back({{2, 1, 6}, 1.f, 0, {0, 0, 0}});
    scene.planes.push_back({{0, 1, 0}, 0.f, 0, {0, 0, 0}});
    scene.lights.push_back({{0, 5, 0}, 0.f, {1, 1, 1}, 0.f});
    scene.materials.push_back(material(0.2f, 1.5f));
    scene.spheres.push_back({{-2, 1, 6}, 1.f, 1, {0, 0, 0}});
    finalizeScene(scene);
    RenderOptions o;
    o.accel = accel;
    o.bounces = 2;
    const float bad[3] = {std::numeric_limits<float>::quiet_NaN(), INFINITY, -INFINITY};
    std::vector<float> rays;
    for (int which = 0; which < 3; ++which)       // origin, direction, both
        for (int v = 0; v < 3; ++v)               // NaN, +Inf, -Inf
            for (int mask = 1; mask < 8; ++mask)  // which components
                for (int i = 0; i < 4; ++i) {
                    float r[6] = {0, 1, 0, 0.1f * float(i - 1), 0, 1};
                    for (int c = 0; c < 3; ++c)
                        if (mask & (1 << c)) {
                            if (which != 1) r[c] = bad[v];
                            if (which != 0) r[3 + c] = bad[v];
                        }
                    rays.insert(rays.end(), r, r + 6);
                }
    size_t n = rays.size() / 6;
    std::vector<float> t;
    std::vector<cl_int2> what;
    closest(cl, scene, o, rays, &t, &what);
    NanResult r;
    r.rays = static_cast<long long>(n);
    int prims[4] = {0, int(scene.spheres.size()), int(scene.planes.size()),
                    int(scene.triangles.size())};
    for (size_t i = 0; i < n; ++i) {
        int kind = what[i].s[0], obj = what[i].s[1];
        if (kind == RT_KIND_MISS) continue;
        if (!(t[i] > 0.f) || !std::isfinite(t[i]) || kind < 0 || kind > 3 || obj < 0 ||
            obj >= prims[kind])
            ++r.badHits;
    }
    SceneProbe shade(cl, scene, o, "Probe_Shade");
    cl::Buffer in = input(cl, rays), out(cl.context(), CL_MEM_WRITE_ONLY, n * 12);
    shade.k.set("rays", in).set("rgb", out);
    shade.run(cl, n);
    std::vector<float> rgb = output<float>(cl, out, n * 3);
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(rgb[i * 3]) || !std::isfinite(rgb[i * 3 + 1]) ||
            !std::isfinite(rgb[i * 3 + 2]))
            ++r.nanPixels;
    return r;
}

// ---- (g) scale sweep ----
// Pixels (of 2/255 or more) by which copies of `scene` scaled by 10^e (core/scene_scale.h)
// differ from the unscaled render in one pipeline, per exponent in `exps`.
std::vector<long long> scaleSweep(ClContext& cl, const Scene& scene, RenderOptions o,
                                  const std::string& kind, const std::vector<int>& exps) {
    std::vector<Scene> copies;  // alive to the end: pipelines key their device copy by address
    for (int e : exps) copies.push_back(scaleScene(scene, std::pow(10.0, e)));
    std::unique_ptr<Pipeline> p = makePipeline(kind, &cl);
    const Image base = p->render(scene, o);
    std::vector<long long> off;
    for (const Scene& c : copies) {
        NestedResult r = compare(p->render(c, o), base);
        off.push_back(r.pixels - r.within);
    }
    return off;
}

// A Blinn-Phong sphere of radius r at distance D straight ahead, lit from the camera: the
// centre pixel (odd image, ray exactly +z) of a device pipeline against the CPU reference.
double farSphereCentreError(ClContext& cl, const std::string& kind, bool robust, double D,
                            double r) {
    Scene s = emptyScene("far-sphere");
    s.spheres.push_back({{0, 0, float(D)}, float(r), 0, {0, 0, 0}});
    s.lights.push_back({{0, 0, 0}, 0.f, {1, 1, 1}, 0.f});
    s.camera.fovY = 0.5f;
    finalizeScene(s);
    RenderOptions o;
    o.width = 41;
    o.height = 31;
    o.bounces = 1;
    o.robustSphere = robust;
    const Image ref = renderReference(s, o), img = makePipeline(kind, &cl)->render(s, o);
    double worst = 0;
    for (int c = 0; c < 3; ++c)
        worst = std::max(worst, double(std::abs(img.pixel(20, 15)[c] - ref.pixel(20, 15)[c])));
    return worst;
}

}  // namespace rt::stress
