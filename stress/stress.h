// rtlab-stress — the numerical stress cases (stress.cpp), shared by the rtlab-stress
// report (stress_main.cpp) and tests/stability_test.cpp, which asserts the robust methods'
// figures on the same functions with fewer rays. Each case counts failures of the plain method
// (the report's algorithm) and of the robust one; the letters are those of stress.cpp's header.
#pragma once

#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "core/cl_runtime.h"
#include "core/scene.h"

namespace rt::stress {

using glm::dvec3;

struct Counts {
    long long rays = 0, bad = 0;
    double rate() const { return rays ? double(bad) / double(rays) : 0.0; }
    Counts& operator+=(const Counts& c) {
        rays += c.rays;
        bad += c.bad;
        return *this;
    }
};

struct LeakResult {
    Counts random, edges, vertices;
};

struct SphereResult {
    Counts misses;     // rays aimed within 0.9 r of the centre that missed
    Counts falseHits;  // rays aimed 1.1 r to 2 r off the centre that hit
};

struct AcneResult {
    Counts meshOut, meshIn, meshEscape, sphereOut, sphereIn, sphereEscape;
};

struct ReintersectResult {
    int triangles = 0, missed = 0, withRehits = 0;
    Counts rehits;
};

struct CriticalResult {
    long long cases = 0, nonFinite = 0, inconsistent = 0, nonUnit = 0, disagree = 0, tirDevice = 0;
};

struct NestedResult {
    long long pixels = 0, nonFinite = 0, within = 0;  // within 2/255 of the CPU reference
    double meanAbs = 0, maxAbs = 0;
};

struct NanResult {
    long long rays = 0, badHits = 0, nanPixels = 0;
};

// A material with the given opacity, index of refraction and reflectance.
dev::Material material(float opacity = 1.f, float ior = 1.f, float reflectance = 0.f);
// A scene with a camera at the origin and nothing in it.
Scene emptyScene(const char* name);

// (a) leaks through a closed mesh centred at `center`.
LeakResult leaks(ClContext& cl, bool watertight, dvec3 center, int randomRays, int rings = 64);
// (b) spheres of `radius` at `distance`, hit by `rays` random rays.
SphereResult tinySpheres(ClContext& cl, bool robust, double distance, double radius, int rays);
// (c) self-intersection at one scale, and pbrt-v4's Triangle.Reintersect.
// The offset methods of core/SHADING.md section 3, in the order the report lists them.
constexpr RenderOptions::Offset kOffsets[] = {
    RenderOptions::Offset::Fixed, RenderOptions::Offset::Scaled, RenderOptions::Offset::Bound};
AcneResult acne(ClContext& cl, double scale, RenderOptions::Offset offset, int primary, int spawn);
ReintersectResult reintersect(ClContext& cl, RenderOptions::Offset offset, double lo, double hi,
                              bool mixed, int triangles, int spawn);
// (d) refraction at the critical angle, and grazing rays per angle.
CriticalResult criticalAngle(ClContext& cl);
std::vector<Counts> grazing(ClContext& cl, bool watertight, int perAngle = 512);
// (e) nested dielectrics through a registered pipeline, against the CPU reference.
NestedResult nested(ClContext& cl, const std::string& pipeline, int width, int height, int bounces);
// (f) NaN and Inf rays through one acceleration structure.
NanResult nanRays(ClContext& cl, RenderOptions::Accel accel);
// (g) pixels (2/255 or more) by which copies of `scene` scaled by 10^e differ from the unscaled
// render in one pipeline, per exponent; and the centre-pixel error of a sphere of radius r at
// distance D against the CPU reference.
std::vector<long long> scaleSweep(ClContext& cl, const Scene& scene, RenderOptions o,
                                  const std::string& pipeline, const std::vector<int>& exps);
double farSphereCentreError(ClContext& cl, const std::string& pipeline, bool robust, double D,
                            double r);

}  // namespace rt::stress
