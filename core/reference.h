// rtlab — the CPU reference renderer: the algorithm of core/SHADING.md in double precision with
// plain recursion, on every core: the renderers' method (renderReference) and the independent
// accuracy oracle (renderOracle).
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "core/image.h"
#include "core/scene.h"

namespace rt {

// Renders the scene with the pipelines' own method (their intersection tests, offsets and
// options) in double precision; threads = 0 uses std::thread::hardware_concurrency().
// progress, when set, is called on the calling thread with rows done (over every pass) and the
// total, ending at the total.
Image renderReference(const Scene& scene, const RenderOptions& options, int threads = 0,
                      const std::function<void(long long done, long long total)>& progress = {});

// The accuracy oracle (core/SHADING.md section 3): the image the algorithm defines, which no
// offset rule can reach. Secondary rays start at the hit point itself and are never offered the
// primitive they leave when it cannot be hit again: a triangle or plane (flat), or a sphere the
// ray leaves outward (convex); a ray into a sphere from its surface gets the far root. Every
// other test takes t > 0 exactly, spheres by the robust test, triangles by the watertight one,
// in double, whatever the options say of offsets and methods. It cannot make the renderers'
// self-intersection mistake, which the method-sharing reference above repeats.
Image renderOracle(const Scene& scene, const RenderOptions& options, int threads = 0,
                   const std::function<void(long long done, long long total)>& progress = {});

// The same image with every primitive tested for every ray, in the order of core/SHADING.md
// section 2 and without the reference's BVHs: the oracle of those structures in the tests.
// Images are bit-identical to renderReference's, minutes later on a large scene.
Image renderReferenceBruteForce(const Scene& scene, const RenderOptions& options, int threads = 0);

// The closest-hit rays (primary, reflection, refraction; shadow rays not counted) of the ray
// trees of each pixel, summed over its AA grid samples, in the order of `pixels`: the shape of
// the work each pixel gives a work-item that traces its whole tree (auto/predict.h). No shading
// is done, so this costs a fraction of rendering those pixels.
std::vector<int> referenceRayTreeSizes(const Scene& scene, const RenderOptions& options,
                                       const std::vector<glm::ivec2>& pixels, int threads = 0);

// The same with the object each pixel's first camera ray hits: RT_KIND_* << 32 | its index, or -1
// on a miss.
struct RayTreeSize {
    int rays = 0;
    long long object = -1;
};
std::vector<RayTreeSize> referenceRayTrees(const Scene& scene, const RenderOptions& options,
                                           const std::vector<glm::ivec2>& pixels, int threads = 0);

// Each pixel's closest-hit rays (its first AA sample's) as a tree: a ray's depth, the material
// it hit (-1 on a miss) and the indices of its children in the same vector (-1 where it spawned
// none), in the order a megakernel's stack traces them: depth first, a ray's reflection and its
// subtree before its refraction. Without shading, like referenceRayTrees.
struct RayTreeNode {
    int depth = 0;
    int material = -1;
    int reflected = -1, refracted = -1;
};
std::vector<std::vector<RayTreeNode>> referenceRayTreeNodes(const Scene& scene,
                                                            const RenderOptions& options,
                                                            const std::vector<glm::ivec2>& pixels,
                                                            int threads = 0);

// Building blocks, exposed for the unit tests. Directions are unit length.
namespace ref {

struct Ray {
    glm::dvec3 origin, dir;
};

// A closest hit: kind is RT_KIND_* (RT_KIND_MISS with t = infinity and object -1 on a miss);
// u, v are a triangle's barycentrics.
struct SceneHit {
    double t;
    int kind, object;
    double u, v;
};

// The reference's ray queries on one scene and its intersection options (robust spheres,
// watertight triangles): through its BVHs, or by brute force over every primitive.
class Queries {
  public:
    Queries(const Scene& scene, const RenderOptions& options, bool bruteForce);
    ~Queries();
    SceneHit closest(const Ray& ray) const;
    // Whether something lies at 0 < t < length along the ray (a shadow ray's test).
    bool occluded(const Ray& ray, double length) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// gamma(n) = n u / (1 - n u) with u = 2^-53: the relative error bound of n double operations.
double gamma(int n);

// Nearest t > 0, or nullopt. Plain = report Algorithm 2 with the "behind the ray" check first.
// conservative: only a t that is positive beyond the test's own rounding error (the device's
// rule, core/SHADING.md section 3); otherwise t > 0 as computed.
std::optional<double> intersectSpherePlain(const Ray& ray, glm::dvec3 center, double radius,
                                           bool conservative = true);
std::optional<double> intersectSphereRobust(const Ray& ray, glm::dvec3 center, double radius,
                                            bool conservative = true);
// The larger root when it is > 0: where a ray from a point of the sphere into it leaves it.
std::optional<double> intersectSphereFar(const Ray& ray, glm::dvec3 center, double radius);

struct TriangleHit {
    double t, u, v;  // barycentrics: p = (1-u-v) v0 + u v1 + v v2
};
std::optional<TriangleHit> intersectTriangleMT(const Ray& ray, glm::dvec3 v0, glm::dvec3 v1,
                                               glm::dvec3 v2, bool conservative = true);
std::optional<TriangleHit> intersectTriangleWatertight(const Ray& ray, glm::dvec3 v0, glm::dvec3 v1,
                                                       glm::dvec3 v2, bool conservative = true);
// The plane n.p = offset.
std::optional<double> intersectPlane(const Ray& ray, glm::dvec3 n, double offset,
                                     bool conservative = true);

glm::dvec3 reflect(glm::dvec3 d, glm::dvec3 n);
// n faces the incoming ray; eta = n1/n2. nullopt on total internal reflection.
std::optional<glm::dvec3> refract(glm::dvec3 d, glm::dvec3 n, double eta);
// cosI = -d.n >= 0. Returns 1 on total internal reflection.
double fresnel(double cosI, double n1, double n2);

}  // namespace ref
}  // namespace rt
