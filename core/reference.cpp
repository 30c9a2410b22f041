// rtlab — the CPU reference renderer: core/SHADING.md in double precision with plain recursion.
// Every OpenCL pipeline is judged against this file, so it follows the spec line by line; the
// only addition is a BVH over the spheres and one over the triangles (planes are infinite and
// tested one by one) that visit every primitive a brute-force loop could accept and break exact
// ties in the brute-force order, so they return bit-identical results, only faster.
#include "core/reference.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

#include "core/procedural.h"
#include "core/reference_bvh.h"
#include "core/sampling.h"

namespace rt {
namespace {

using glm::dvec3;
using ref::Ray;

dvec3 toD(const dev::Float3& f) { return dvec3(f.x, f.y, f.z); }

struct Hit {
    double t = std::numeric_limits<double>::infinity();
    int kind = RT_KIND_MISS;
    int object = -1;
    double u = 0, v = 0;  // triangle barycentrics
};

// The primitive a secondary ray leaves, for the oracle (renderOracle): flat primitives are not
// offered to it again, a sphere only when the ray goes into it (then by its far root).
struct Source {
    int kind = RT_KIND_MISS;
    int object = -1;
    bool outward = true;  // leaves a sphere's outside (its outward normal's side)
    glm::dvec3 away{0};   // flat primitives: the side of the plane the ray was spawned on
};

struct Surface {
    int kind, object;
    dvec3 p, n;
    dvec3 ng;   // geometric normal, facing the incoming ray like n
    dvec3 err;  // per-component bound on the rounding error of p (bound offset)
    bool inside;
    int material;
};

class Tracer {
  public:
    Tracer(const Scene& scene, const RenderOptions& options, bool bruteForce, bool oracle = false)
        : scene_(scene),
          opt_(options),
          bruteForce_(bruteForce),
          oracle_(oracle),
          spheres_(bruteForce ? refbvh::Bvh() : refbvh::Bvh::overSpheres(scene.spheres)),
          triangles_(bruteForce ? refbvh::Bvh() : refbvh::Bvh::overTriangles(scene.triangles)) {}

    // AA sample `sample` (sy n + sx, as the device numbers them) at offset (ox, oy) in the pixel.
    dvec3 pixel(int x, int y, int sample, double ox, double oy) const {
        return trace(Ray{toD(scene_.camera.position), primaryDir(x + ox, y + oy)}, Source{}, 0,
                     PixelSample{x, y, sample});
    }

    // Section 2: spheres, planes, triangles; replace only on 0 < t < tBest, so exact ties keep
    // the first object in that order. The BVHs offer primitives in their own order, and planes
    // go first there to bound the traversals; an exact tie then goes to the object a loop in
    // section 2's order would have kept (better), so the hit is the same.
    Hit closestHit(const Ray& ray, const Source& from = {}) const {
        if (intoSource(ray, from)) return backAtSource(ray, from);
        Hit best;
        if (bruteForce_) {
            for (std::size_t i = 0; i < scene_.spheres.size(); ++i) {
                const auto t = sphereT(ray, int(i), from);
                if (t && *t > 0 && *t < best.t) best = Hit{*t, RT_KIND_SPHERE, int(i)};
            }
            for (std::size_t i = 0; i < scene_.planes.size(); ++i) {
                const auto t = planeT(ray, int(i), from);
                if (t && *t > 0 && *t < best.t) best = Hit{*t, RT_KIND_PLANE, int(i)};
            }
            for (std::size_t i = 0; i < scene_.triangles.size(); ++i) {
                const auto h = triangleHit(ray, int(i), from);
                if (h && h->t > 0 && h->t < best.t)
                    best = Hit{h->t, RT_KIND_TRIANGLE, int(i), h->u, h->v};
            }
            return best;
        }
        for (std::size_t i = 0; i < scene_.planes.size(); ++i) {
            const auto t = planeT(ray, int(i), from);
            if (t && better(*t, RT_KIND_PLANE, int(i), best)) best = Hit{*t, RT_KIND_PLANE, int(i)};
        }
        spheres_.traverse(
            ray,
            [&](int i) {
                const auto t = sphereT(ray, i, from);
                if (t && better(*t, RT_KIND_SPHERE, i, best)) best = Hit{*t, RT_KIND_SPHERE, i};
                return best.t;
            },
            best.t);
        triangles_.traverse(
            ray,
            [&](int i) {
                const auto h = triangleHit(ray, i, from);
                if (h && better(h->t, RT_KIND_TRIANGLE, i, best))
                    best = Hit{h->t, RT_KIND_TRIANGLE, i, h->u, h->v};
                return best.t;
            },
            best.t);
        return best;
    }

    // Section 4: any hit with 0 < t < length blocks the shadow ray.
    bool occluded(const Ray& ray, double length, const Source& from = {}) const {
        if (intoSource(ray, from)) return true;
        auto blocks = [&](const std::optional<double>& t) { return t && *t > 0 && *t < length; };
        for (std::size_t i = 0; i < scene_.planes.size(); ++i)
            if (blocks(planeT(ray, int(i), from))) return true;
        if (bruteForce_) {
            for (std::size_t i = 0; i < scene_.spheres.size(); ++i)
                if (blocks(sphereT(ray, int(i), from))) return true;
            for (std::size_t i = 0; i < scene_.triangles.size(); ++i) {
                const auto h = triangleHit(ray, int(i), from);
                if (h && blocks(h->t)) return true;
            }
            return false;
        }
        bool blocked = false;
        // A negative bound ends a traversal.
        spheres_.traverse(
            ray,
            [&](int i) {
                blocked = blocks(sphereT(ray, i, from));
                return blocked ? -1.0 : length;
            },
            length);
        if (blocked) return true;
        triangles_.traverse(
            ray,
            [&](int i) {
                const auto h = triangleHit(ray, i, from);
                blocked = h && blocks(h->t);
                return blocked ? -1.0 : length;
            },
            length);
        return blocked;
    }

  private:
    // Whether a hit at t on object `object` of `kind` replaces `best`: nearer, or exactly as near
    // and first in section 2's order (spheres, planes, triangles, each by index; the RT_KIND_*
    // values are in that order). A miss is never tied: nothing is kept at t = infinity.
    static bool better(double t, int kind, int object, const Hit& best) {
        if (!(t > 0) || !(t <= best.t)) return false;
        if (t < best.t) return true;
        if (best.kind == RT_KIND_MISS) return false;
        return kind < best.kind || (kind == best.kind && object < best.object);
    }

    // Section 1: camera space, then pitch around x, then yaw around y.
    dvec3 primaryDir(double px, double py) const {
        const dev::Camera& cam = scene_.camera;
        const double w = opt_.width, h = opt_.height;
        const double dist = 1 / std::tan(double(cam.fovY) / 2);
        const dvec3 nc((2 * px / w - 1) * (w / h), 1 - 2 * py / h, dist);
        const double ca = std::cos(double(cam.pitch)), sa = std::sin(double(cam.pitch));
        const dvec3 o(nc.x, nc.y * ca + nc.z * sa, nc.z * ca - nc.y * sa);
        const double cb = std::cos(double(cam.yaw)), sb = std::sin(double(cam.yaw));
        return glm::normalize(dvec3(o.x * cb + o.z * sb, o.y, o.z * cb - o.x * sb));
    }

    // Whether the oracle keeps primitive (kind, i) from a ray that leaves `from`.
    bool leaves(const Source& from, int kind, int i) const {
        return oracle_ && from.kind == kind && from.object == i;
    }

    std::optional<double> sphereT(const Ray& ray, int i, const Source& from) const {
        const dev::Sphere& s = scene_.spheres[std::size_t(i)];
        if (oracle_) {
            if (!leaves(from, RT_KIND_SPHERE, i))
                return ref::intersectSphereRobust(ray, toD(s.center), s.radius, false);
            if (from.outward) return std::nullopt;
            return ref::intersectSphereFar(ray, toD(s.center), s.radius);
        }
        return opt_.robustSphere ? ref::intersectSphereRobust(ray, toD(s.center), s.radius)
                                 : ref::intersectSpherePlain(ray, toD(s.center), s.radius);
    }

    // The oracle's flat rule: a ray meets a plane through its own origin only at t = 0, so a flat
    // primitive whose plane passes within 1e-12 of the coordinates' size of the origin (1e4
    // times the double rounding of a point on it) is not offered. This covers the primitive the
    // ray leaves, and any coplanar neighbour or overlapping twin (concave NFF polygons, fanned,
    // overlap themselves), where skipping the source alone would meet the twin at t ~ 1e-16.
    static bool throughOrigin(const Ray& ray, dvec3 n, double offset, double size) {
        return std::abs(glm::dot(n, ray.origin) - offset) <= 1e-12 * glm::length(n) * size;
    }

    std::optional<double> planeT(const Ray& ray, int i, const Source& from) const {
        if (leaves(from, RT_KIND_PLANE, i)) return std::nullopt;
        const dev::Plane& pl = scene_.planes[std::size_t(i)];
        const dvec3 n = toD(pl.normal);
        const double o = double(pl.offset);
        if (oracle_ && throughOrigin(ray, n, o, std::max(maxAbs(ray.origin), std::abs(o))))
            return std::nullopt;
        return ref::intersectPlane(ray, n, o, !oracle_);
    }

    static double maxAbs(dvec3 v) {
        return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    }

    std::optional<ref::TriangleHit> triangleHit(const Ray& ray, int i, const Source& from) const {
        if (leaves(from, RT_KIND_TRIANGLE, i)) return std::nullopt;
        const dev::Triangle& tr = scene_.triangles[std::size_t(i)];
        if (oracle_) {
            const dvec3 v0 = toD(tr.v0), v1 = toD(tr.v1), v2 = toD(tr.v2);
            const dvec3 n = glm::cross(v1 - v0, v2 - v0);
            const double size = std::max({maxAbs(ray.origin), maxAbs(v0), maxAbs(v1), maxAbs(v2)});
            if (throughOrigin(ray, n, glm::dot(n, v0), size)) return std::nullopt;
            return ref::intersectTriangleWatertight(ray, v0, v1, v2, false);
        }
        return opt_.watertight
                   ? ref::intersectTriangleWatertight(ray, toD(tr.v0), toD(tr.v1), toD(tr.v2))
                   : ref::intersectTriangleMT(ray, toD(tr.v0), toD(tr.v1), toD(tr.v2));
    }

    // A ray spawned on one side of a flat primitive whose direction points into its other side
    // (a shading normal bends the reflection or the light below the geometric plane): the limit
    // of a vanishing offset meets the primitive itself at t -> 0, which the oracle returns.
    bool intoSource(const Ray& ray, const Source& from) const {
        return oracle_ && (from.kind == RT_KIND_TRIANGLE || from.kind == RT_KIND_PLANE) &&
               glm::dot(ray.dir, from.away) < 0;
    }

    Hit backAtSource(const Ray& ray, const Source& from) const {
        Hit h{0, from.kind, from.object};
        if (from.kind == RT_KIND_TRIANGLE) {  // the origin's barycentrics, by areas
            const dev::Triangle& tr = scene_.triangles[std::size_t(from.object)];
            const dvec3 v0 = toD(tr.v0), e1 = toD(tr.v1) - v0, e2 = toD(tr.v2) - v0;
            const dvec3 n = glm::cross(e1, e2), q = ray.origin - v0;
            const double nn = glm::dot(n, n);
            h.u = glm::dot(glm::cross(q, e2), n) / nn;
            h.v = glm::dot(glm::cross(e1, q), n) / nn;
        }
        return h;
    }

    // The primitive a ray spawned at s on `side` (section 3) leaves.
    static Source source(const Surface& s, double side) {
        return Source{s.kind, s.object, (side > 0) != s.inside, side * s.ng};
    }

    // Section 2, normals: the shading normal faces the incoming ray; inside when flipped. Hit
    // points and normals as the device computes them (core/cl/raytree.cl), in double.
    Surface surface(const Ray& ray, const Hit& hit) const {
        Surface s;
        s.kind = hit.kind, s.object = hit.object;
        s.p = ray.origin + hit.t * ray.dir;
        s.ng = dvec3(0);
        // The oracle's points are the bound rule's: on the surface to its own rounding.
        const bool bound = oracle_ || opt_.offset == RenderOptions::Offset::Bound;
        if (hit.kind == RT_KIND_TRIANGLE) {
            const dev::Triangle& tr = scene_.triangles[hit.object];
            const dvec3 v0 = toD(tr.v0), v1 = toD(tr.v1), v2 = toD(tr.v2);
            const dvec3 ng = glm::cross(v1 - v0, v2 - v0);
            const double w = 1 - hit.u - hit.v;
            const dvec3 ns =
                glm::normalize(w * toD(tr.n0) + hit.u * toD(tr.n1) + hit.v * toD(tr.n2));
            if (bound) s.p = w * v0 + hit.u * v1 + hit.v * v2;
            s.inside = glm::dot(ng, ray.dir) > 0;
            s.n = s.inside ? -ns : ns;
            s.ng = glm::normalize(s.inside ? -ng : ng);
            s.err = gamma(7) * (glm::abs(v0) + glm::abs(v1) + glm::abs(v2));
            s.material = tr.material;
            return s;
        }
        dvec3 n;
        if (hit.kind == RT_KIND_SPHERE) {
            const dev::Sphere& sp = scene_.spheres[hit.object];
            const dvec3 c = toD(sp.center);
            if (oracle_ || opt_.robustSphere) {
                n = sphereNormal(ray, c, sp.radius, hit.t);
                s.p = c + double(sp.radius) * n;
            } else {
                n = (s.p - c) / double(sp.radius);  // the report's normal
                if (bound) s.p = c + double(sp.radius) * glm::normalize(n);
            }
            s.err = gamma(5) * (glm::abs(c) + double(sp.radius) * glm::abs(glm::normalize(n)));
            s.material = sp.material;
        } else {
            const dev::Plane& pl = scene_.planes[hit.object];
            n = toD(pl.normal);
            if (bound) s.p += (double(pl.offset) - glm::dot(n, s.p)) * n;
            s.err = gamma(6) * (glm::abs(s.p) + std::abs(double(pl.offset)));
            s.material = pl.material;
        }
        s.inside = glm::dot(n, ray.dir) > 0;
        s.n = s.inside ? -n : n;
        s.ng = s.n;
        return s;
    }

    // Section 2, robust spheres: p - c = f -/+ h d with f's component along d projected out.
    static dvec3 sphereNormal(const Ray& ray, dvec3 c, double r, double t) {
        const dvec3 oc = ray.origin - c;
        const double b = -glm::dot(oc, ray.dir);
        dvec3 f = oc + b * ray.dir;
        f -= glm::dot(f, ray.dir) * ray.dir;
        const double h = std::sqrt(std::max(r * r - glm::dot(f, f), 0.0));
        return glm::normalize(t < b ? f - h * ray.dir : f + h * ray.dir);
    }

    // gamma(n) of double arithmetic (u = 2^-53): the reference's error bounds are those of its
    // own rounding, about 5e8 times below the device's, so its bound offset is the limit of a
    // vanishing offset that the float pipelines approach (core/SHADING.md section 3).
    static double gamma(int n) { return ref::gamma(n); }

    // Section 3: where a secondary ray leaves s, on the normal's side (side 1) or the other.
    // The oracle spawns at the point itself (its rays skip what they leave, Source).
    dvec3 spawn(const Surface& s, double side) const {
        if (oracle_) return s.p;
        if (opt_.offset == RenderOptions::Offset::Fixed) return s.p + side * 1e-4 * s.n;
        if (opt_.offset == RenderOptions::Offset::Scaled)
            return s.p + side * 1e-4 *
                             std::max({1.0, std::abs(s.p.x), std::abs(s.p.y), std::abs(s.p.z)}) *
                             s.n;
        const dvec3 w = side * s.ng;
        dvec3 o = s.p + glm::dot(glm::abs(s.ng), s.err) * w;
        for (int i = 0; i < 3; ++i)
            if (w[i] != 0) o[i] = std::nextafter(o[i], w[i] > 0 ? HUGE_VAL : -HUGE_VAL);
        return o;
    }

    // Section 4: visibility of light j from p, in [1 - strength, 1]. The samples on the light's
    // disk are the device's (core/sampling.h), keyed by the pixel, AA sample and depth.
    double visibility(const Surface& s, int j, dvec3 o, uint32_t key) const {
        const dev::Light& light = scene_.lights[size_t(j)];
        const dvec3 c = toD(light.position);
        int samples = 1;
        if (light.radius > 0) samples = opt_.shadowSamples;
        dvec3 t(0), b(0);
        if (light.radius > 0) {
            // Duff et al. 2017, "Building an Orthonormal Basis, Revisited".
            const dvec3 w = glm::normalize(c - s.p);
            const double sign = w.z >= 0 ? 1.0 : -1.0;
            const double a = -1 / (sign + w.z);
            const double bb = w.x * w.y * a;
            t = dvec3(1 + sign * w.x * w.x * a, sign * bb, -sign * w.x);
            b = dvec3(bb, sign + w.y * w.y * a, -w.y);
        }
        int blocked = 0;
        for (int k = 0; k < samples; ++k) {
            dvec3 q = c;
            if (light.radius > 0) {
                const DiskSample ds = shadowDiskSample(key, j, k, samples);
                const double rho = double(light.radius) * ds.radius;
                q = c + rho * (std::cos(ds.angle) * t + std::sin(ds.angle) * b);
            }
            const double length = glm::length(q - o);
            if (occluded(Ray{o, (q - o) / length}, length, source(s, 1))) ++blocked;
        }
        return 1 - double(opt_.shadowStrength) * blocked / samples;
    }

    // Section 5: Blinn-Phong with shadowed lights.
    // Procedural materials change D and the shading normal only; shadow rays keep s.n.
    dvec3 base(const Surface& s, dvec3 d, const dev::Material& m, dvec3 origin,
               uint32_t key) const {
        dvec3 colour = toD(m.ambient), diffuse = toD(m.diffuse), n = s.n;
        if (m.pattern != RT_PATTERN_NONE) proc::apply(m, s.p, diffuse, n);
        for (size_t j = 0; j < scene_.lights.size(); ++j) {
            const dev::Light& light = scene_.lights[j];
            const dvec3 l = glm::normalize(toD(light.position) - s.p);
            const double nl = glm::dot(n, l);
            if (!(nl > 0)) continue;
            const dvec3 h = glm::normalize(l - d);
            const double spec = std::pow(std::max(glm::dot(n, h), 0.0), double(m.exponent));
            // The device counts no shadow rays toward a light behind the geometric normal.
            const double vis = glm::dot(s.n, l) > 0 ? visibility(s, int(j), origin, key) : 1.0;
            colour += vis * toD(light.color) * (diffuse * nl + toD(m.specular) * spec);
        }
        return colour;
    }

    // Section 9: sky gradient or cubemap.
    dvec3 environment(dvec3 d) const {
        const Environment& env = scene_.environment;
        if (env.cubemapSize > 0 && !env.cubemap.empty()) return cubemap(d);
        const dvec3 horizon = toD(env.horizon);
        if (d.y >= 0) return horizon + (toD(env.zenith) - horizon) * d.y;
        return horizon + (toD(env.ground) - horizon) * (-d.y);
    }

    dvec3 cubemap(dvec3 d) const {
        const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
        int face;
        double sc, tc, ma;
        if (ax >= ay && ax >= az) {
            face = d.x >= 0 ? 0 : 1;
            sc = d.x >= 0 ? -d.z : d.z, tc = -d.y, ma = ax;
        } else if (ay >= az) {
            face = d.y >= 0 ? 2 : 3;
            sc = d.x, tc = d.y >= 0 ? d.z : -d.z, ma = ay;
        } else {
            face = d.z >= 0 ? 4 : 5;
            sc = d.z >= 0 ? d.x : -d.x, tc = -d.y, ma = az;
        }
        const int size = scene_.environment.cubemapSize;
        const double u = (sc / ma + 1) / 2, v = (tc / ma + 1) / 2;
        const double fx = std::clamp(u * size - 0.5, 0.0, size - 1.0);
        const double fy = std::clamp(v * size - 0.5, 0.0, size - 1.0);
        const int x0 = int(fx), y0 = int(fy);
        const int x1 = std::min(x0 + 1, size - 1), y1 = std::min(y0 + 1, size - 1);
        const double wx = fx - x0, wy = fy - y0;
        const float* texels =
            scene_.environment.cubemap.data() + std::size_t(face) * size * size * 3;
        auto texel = [&](int x, int y) {
            const float* p = texels + (std::size_t(y) * size + x) * 3;
            return dvec3(p[0], p[1], p[2]);
        };
        return (1 - wy) * ((1 - wx) * texel(x0, y0) + wx * texel(x1, y0)) +
               wy * ((1 - wx) * texel(x0, y1) + wx * texel(x1, y1));
    }

    // Sections 6 and 8: children at depth < B, combined with Fresnel or reflectance weights.
    struct PixelSample {
        int x, y, sample;
    };

    // Section 6: the rays a hit spawns below depth B (the reflection of a mirror or of glass, and
    // glass's refraction unless it reflects totally), and the weights that combine them: f for
    // the reflection, o for the surface's own colour against the refraction.
    struct Children {
        std::optional<Ray> reflected, refracted;
        Source reflectedFrom, refractedFrom;
        double f = 0, o = 1;
    };

    Children children(const Surface& s, const dev::Material& m, dvec3 d, int depth) const {
        Children c;
        if (depth >= opt_.bounces) return c;
        const bool transparent = m.opacity < 1;
        const double n1 = s.inside ? double(m.ior) : 1.0;
        const double n2 = s.inside ? 1.0 : double(m.ior);
        if (m.reflectance > 0 || transparent) {
            c.reflected = Ray{spawn(s, 1), ref::reflect(d, s.n)};
            c.reflectedFrom = source(s, 1);
            c.f = transparent ? ref::fresnel(-glm::dot(d, s.n), n1, n2) : double(m.reflectance);
        }
        if (transparent) {
            if (const auto t = ref::refract(d, s.n, n1 / n2)) {
                c.refracted = Ray{spawn(s, -1), *t};
                c.refractedFrom = source(s, -1);
                c.o = m.opacity;
            }
        }
        return c;
    }

    dvec3 trace(const Ray& ray, const Source& from, int depth, PixelSample px) const {
        const Hit hit = closestHit(ray, from);
        if (hit.kind == RT_KIND_MISS) return environment(ray.dir);
        const Surface s = surface(ray, hit);
        const dev::Material& m = scene_.materials[s.material];
        const dvec3 d = ray.dir;
        const uint32_t key = dev::Sampling_PointKey(px.x, px.y, px.sample, depth);
        const dvec3 baseColour = base(s, d, m, spawn(s, 1), key);
        const Children c = children(s, m, d, depth);
        const dvec3 reflected =
            c.reflected ? trace(*c.reflected, c.reflectedFrom, depth + 1, px) : dvec3(0);
        const dvec3 refracted =
            c.refracted ? trace(*c.refracted, c.refractedFrom, depth + 1, px) : dvec3(0);
        const dvec3 through = c.o * baseColour + (1 - c.o) * refracted;
        return (1 - c.f) * through + c.f * reflected;
    }

  public:
    // The closest-hit rays of one AA sample's ray tree (itself and every child), without shading
    // it: the shape of the tree alone.
    // `hit`, when set, receives the object the camera ray hits (RayTreeSize::object).
    int treeSize(int x, int y, double ox, double oy, long long* hit = nullptr) const {
        return treeSize(Ray{toD(scene_.camera.position), primaryDir(x + ox, y + oy)}, 0, hit);
    }

    void treeNodes(int x, int y, double ox, double oy, std::vector<RayTreeNode>& out) const {
        treeNodes(Ray{toD(scene_.camera.position), primaryDir(x + ox, y + oy)}, 0, out);
    }

  private:
    int treeSize(const Ray& ray, int depth, long long* primary = nullptr) const {
        const Hit hit = closestHit(ray);
        if (primary)
            *primary = hit.kind == RT_KIND_MISS ? -1 : (long long)(hit.kind) << 32 | hit.object;
        if (hit.kind == RT_KIND_MISS) return 1;
        const Surface s = surface(ray, hit);
        const Children c = children(s, scene_.materials[s.material], ray.dir, depth);
        return 1 + (c.reflected ? treeSize(*c.reflected, depth + 1) : 0) +
               (c.refracted ? treeSize(*c.refracted, depth + 1) : 0);
    }

    // Appends the tree of `ray` to `out` depth first, reflection first; returns its root's index.
    int treeNodes(const Ray& ray, int depth, std::vector<RayTreeNode>& out) const {
        const int at = int(out.size());
        out.push_back({depth, -1, -1, -1});
        const Hit hit = closestHit(ray);
        if (hit.kind == RT_KIND_MISS) return at;
        const Surface s = surface(ray, hit);
        out[std::size_t(at)].material = s.material;
        const Children c = children(s, scene_.materials[s.material], ray.dir, depth);
        if (c.reflected) {
            const int child = treeNodes(*c.reflected, depth + 1, out);
            out[std::size_t(at)].reflected = child;
        }
        if (c.refracted) {
            const int child = treeNodes(*c.refracted, depth + 1, out);
            out[std::size_t(at)].refracted = child;
        }
        return at;
    }

    const Scene& scene_;
    const RenderOptions& opt_;
    bool bruteForce_;
    bool oracle_;
    refbvh::Bvh spheres_, triangles_;
};

// Runs fn(row) for every row, rows handed out by an atomic counter; after each of its own rows
// the calling thread calls done(rows finished by all threads).
template <class Fn, class Done>
void forEachRow(int height, int threads, const Fn& fn, const Done& done) {
    std::atomic<int> next{0}, finished{0};
    auto worker = [&](bool report) {
        for (int y = next++; y < height; y = next++) {
            fn(y);
            int rows = ++finished;
            if (report) done(rows);
        }
    };
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker, false);
    worker(true);
    for (std::thread& t : pool) t.join();
    done(height);
}

void store(Image& image, int x, int y, dvec3 c) {
    float* p = image.pixel(x, y);
    p[0] = float(c.x), p[1] = float(c.y), p[2] = float(c.z);
}

Image render(const Scene& scene, const RenderOptions& options, int threads,
             const std::function<void(long long, long long)>& progress, bool bruteForce,
             bool oracle = false) {
    if (threads <= 0) threads = int(std::max(1u, std::thread::hardware_concurrency()));
    threads = std::min(threads, std::max(1, options.height));
    const Tracer tracer(scene, options, bruteForce, oracle);
    const int n = std::max(1, options.aa);
    Image image(options.width, options.height);

    // Section 1: sub-pixel samples sy outer, sx inner, summed, then divided by n*n.
    auto fullGrid = [&](int x, int y) {
        dvec3 sum(0);
        for (int sy = 0; sy < n; ++sy)
            for (int sx = 0; sx < n; ++sx)
                sum += tracer.pixel(x, y, sy * n + sx, (sx + 0.5) / n, (sy + 0.5) / n);
        return sum / double(n * n);
    };

    // Rows x passes; a row is reported once, however many threads finish rows meanwhile.
    const bool adaptive = options.adaptiveAa && n > 1;
    const long long total = (long long)(options.height) * (adaptive ? 2 : 1);
    long long reported = 0, passStart = 0;
    auto done = [&](int rows) {
        if (progress && passStart + rows > reported) progress(reported = passStart + rows, total);
    };
    if (!adaptive) {
        forEachRow(
            options.height, threads,
            [&](int y) {
                for (int x = 0; x < options.width; ++x) store(image, x, y, fullGrid(x, y));
            },
            done);
        return image;
    }

    // Section 11: centre samples, then the full grid where a 4-neighbour differs by > 0.1.
    forEachRow(
        options.height, threads,
        [&](int y) {
            for (int x = 0; x < options.width; ++x)
                store(image, x, y, tracer.pixel(x, y, 0, 0.5, 0.5));
        },
        done);
    passStart = options.height;
    const Image centre = image;
    auto differs = [&](int x, int y, int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= centre.width || ny >= centre.height) return false;
        const float* a = centre.pixel(x, y);
        const float* b = centre.pixel(nx, ny);
        for (int c = 0; c < 3; ++c)
            if (std::abs(a[c] - b[c]) > 0.1f) return true;
        return false;
    };
    forEachRow(
        options.height, threads,
        [&](int y) {
            for (int x = 0; x < options.width; ++x) {
                if (differs(x, y, x - 1, y) || differs(x, y, x + 1, y) || differs(x, y, x, y - 1) ||
                    differs(x, y, x, y + 1))
                    store(image, x, y, fullGrid(x, y));
            }
        },
        done);
    return image;
}

}  // namespace

Image renderReference(const Scene& scene, const RenderOptions& options, int threads,
                      const std::function<void(long long, long long)>& progress) {
    return render(scene, options, threads, progress, false);
}

Image renderOracle(const Scene& scene, const RenderOptions& options, int threads,
                   const std::function<void(long long, long long)>& progress) {
    return render(scene, options, threads, progress, false, true);
}

Image renderReferenceBruteForce(const Scene& scene, const RenderOptions& options, int threads) {
    return render(scene, options, threads, {}, true);
}

// Runs fn(i) for every i in [0, n), in chunks handed out by an atomic counter to `threads`
// threads (0: one a core).
template <class Fn>
void forEachIndex(std::size_t n, int threads, const Fn& fn) {
    if (threads <= 0) threads = int(std::max(1u, std::thread::hardware_concurrency()));
    std::atomic<std::size_t> next{0};
    constexpr std::size_t kChunk = 64;
    auto worker = [&] {
        for (std::size_t begin = next.fetch_add(kChunk); begin < n; begin = next.fetch_add(kChunk))
            for (std::size_t i = begin; i < std::min(n, begin + kChunk); ++i) fn(i);
    };
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
}

std::vector<RayTreeSize> referenceRayTrees(const Scene& scene, const RenderOptions& options,
                                           const std::vector<glm::ivec2>& pixels, int threads) {
    const Tracer tracer(scene, options, false);
    const int n = std::max(1, options.aa);
    std::vector<RayTreeSize> trees(pixels.size());
    forEachIndex(pixels.size(), threads, [&](std::size_t i) {
        RayTreeSize& t = trees[i];
        for (int sy = 0; sy < n; ++sy)
            for (int sx = 0; sx < n; ++sx)
                t.rays += tracer.treeSize(pixels[i].x, pixels[i].y, (sx + 0.5) / n, (sy + 0.5) / n,
                                          sx + sy == 0 ? &t.object : nullptr);
    });
    return trees;
}

std::vector<std::vector<RayTreeNode>> referenceRayTreeNodes(const Scene& scene,
                                                            const RenderOptions& options,
                                                            const std::vector<glm::ivec2>& pixels,
                                                            int threads) {
    const Tracer tracer(scene, options, false);
    const double offset = 0.5 / std::max(1, options.aa);  // the first sample of the AA grid
    std::vector<std::vector<RayTreeNode>> trees(pixels.size());
    forEachIndex(pixels.size(), threads, [&](std::size_t i) {
        tracer.treeNodes(pixels[i].x, pixels[i].y, offset, offset, trees[i]);
    });
    return trees;
}

std::vector<int> referenceRayTreeSizes(const Scene& scene, const RenderOptions& options,
                                       const std::vector<glm::ivec2>& pixels, int threads) {
    std::vector<int> sizes;
    for (const RayTreeSize& t : referenceRayTrees(scene, options, pixels, threads))
        sizes.push_back(t.rays);
    return sizes;
}

namespace ref {

struct Queries::Impl {
    Impl(const Scene& scene, const RenderOptions& options, bool bruteForce)
        : options(options), tracer(scene, this->options, bruteForce) {}
    RenderOptions options;
    Tracer tracer;
};

Queries::Queries(const Scene& scene, const RenderOptions& options, bool bruteForce)
    : impl_(std::make_unique<Impl>(scene, options, bruteForce)) {}

Queries::~Queries() = default;

SceneHit Queries::closest(const Ray& ray) const {
    const Hit h = impl_->tracer.closestHit(ray);
    return SceneHit{h.t, h.kind, h.object, h.u, h.v};
}

bool Queries::occluded(const Ray& ray, double length) const {
    return impl_->tracer.occluded(ray, length);
}

}  // namespace ref
}  // namespace rt
