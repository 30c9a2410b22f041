// rtlab — the CPU reference's ray/primitive tests and secondary-ray directions (core/SHADING.md
// sections 2, 6 and 7) in double precision. Each test is the device's (core/cl/intersect.cl)
// line by line, with the same conservative t > 0 in its own rounding (u = 2^-53) when
// `conservative` is set; the independent oracle (renderOracle) tests t > 0 exactly instead and
// never offers a ray the primitive it leaves.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/reference.h"

namespace rt::ref {

using glm::dvec3;

double gamma(int n) {
    const double nu = n * std::numeric_limits<double>::epsilon() / 2;
    return nu / (1 - nu);
}

// Section 2, Algorithm 2 with a = 1. One of -b -/+ s cancels: its error is the discriminant's
// over 2 s, and a root at or below it is not trusted to be positive.
std::optional<double> intersectSpherePlain(const Ray& ray, dvec3 center, double radius,
                                           bool conservative) {
    const dvec3 oc = ray.origin - center;
    const double doc = glm::dot(ray.dir, oc);
    const double c = glm::dot(oc, oc) - radius * radius;
    if (c > 0 && doc > 0) return std::nullopt;  // origin outside, sphere behind the ray
    const double b = 2 * doc;
    const double disc = b * b - 4 * c;
    if (disc < 0) return std::nullopt;
    const double s = std::sqrt(disc);
    const double t0 = (-b - s) / 2, t1 = (-b + s) / 2;
    // t > dt / s, as the device compares it (t s > dt); |oc|^2 + r^2 = c + 2 r^2.
    const double dt = conservative ? gamma(13) * (b * b + 4 * (c + 2 * radius * radius)) : 0;
    if (t0 * s > dt || (!conservative && t0 > 0)) return t0;
    if (t1 * s > dt || (!conservative && t1 > 0)) return t1;
    return std::nullopt;
}

// Section 2, Ray Tracing Gems ch. 7: the discriminant from the perpendicular distance f. The
// root c / q is the one near 0 for a ray that leaves the sphere; c is off by up to
// gamma(6) (|oc|^2 + r^2).
std::optional<double> intersectSphereRobust(const Ray& ray, dvec3 center, double radius,
                                            bool conservative) {
    const dvec3 oc = ray.origin - center;
    const double doc = glm::dot(ray.dir, oc);
    const double c = glm::dot(oc, oc) - radius * radius;
    if (c > 0 && doc > 0) return std::nullopt;
    const double bp = -doc;
    const dvec3 f = oc + bp * ray.dir;
    const double disc = radius * radius - glm::dot(f, f);
    if (disc < 0) return std::nullopt;
    const double q = bp + (bp >= 0 ? 1.0 : -1.0) * std::sqrt(disc);
    // c / q > gamma(8) (|oc|^2 + r^2) / |q|, as the device compares it (without the division).
    const double tc = c / q, tq = q;
    const bool okc =
        conservative ? (q > 0 ? c : -c) > gamma(8) * (c + 2 * radius * radius) : tc > 0;
    const bool okq = tq > 0;
    if (okc && okq) return std::min(tc, tq);
    if (okc) return tc;
    if (okq) return tq;
    return std::nullopt;
}

// The far root of the robust test: where a ray that starts on the sphere and enters it leaves
// it again (the oracle's refraction and inside rays; the near root is the start itself).
std::optional<double> intersectSphereFar(const Ray& ray, dvec3 center, double radius) {
    const dvec3 oc = ray.origin - center;
    const double bp = -glm::dot(ray.dir, oc);
    const dvec3 f = oc + bp * ray.dir;
    const double disc = radius * radius - glm::dot(f, f);
    if (disc < 0) return std::nullopt;
    const double q = bp + (bp >= 0 ? 1.0 : -1.0) * std::sqrt(disc);
    const double t = std::max((glm::dot(oc, oc) - radius * radius) / q, q);
    if (t > 0) return t;
    return std::nullopt;
}

// Section 2, Algorithm 3 with the two report typos fixed; t is trusted past gamma(9) |f|
// |e2|.(|s| x |e1|) (core/cl/intersect.cl derives it).
std::optional<TriangleHit> intersectTriangleMT(const Ray& ray, dvec3 v0, dvec3 v1, dvec3 v2,
                                               bool conservative) {
    const dvec3 e1 = v1 - v0, e2 = v2 - v0;
    const dvec3 h = glm::cross(ray.dir, e2);
    const double a = glm::dot(e1, h);
    if (a == 0) return std::nullopt;
    const double f = 1 / a;
    const dvec3 s = ray.origin - v0;
    const double u = f * glm::dot(s, h);
    if (u < 0 || u > 1) return std::nullopt;
    const dvec3 q = glm::cross(s, e1);
    const double v = f * glm::dot(ray.dir, q);
    if (v < 0 || u + v > 1) return std::nullopt;
    const double t = f * glm::dot(e2, q);
    double dt = 0;
    if (conservative) {
        const dvec3 as = glm::abs(s), ae = glm::abs(e1);
        const dvec3 bound(as.y * ae.z + as.z * ae.y, as.z * ae.x + as.x * ae.z,
                          as.x * ae.y + as.y * ae.x);
        dt = gamma(9) * std::abs(f) * glm::dot(glm::abs(e2), bound);
    }
    if (!(t > dt)) return std::nullopt;
    return TriangleHit{t, u, v};
}

// Section 2, Woop, Benthin and Wald 2013: shear into ray space, 2D edge functions; pbrt-v4's
// conservative bound on t (section 6.8.7 of its book).
std::optional<TriangleHit> intersectTriangleWatertight(const Ray& ray, dvec3 v0, dvec3 v1, dvec3 v2,
                                                       bool conservative) {
    const dvec3& d = ray.dir;
    int kz = 0;
    if (std::abs(d.y) > std::abs(d[kz])) kz = 1;
    if (std::abs(d.z) > std::abs(d[kz])) kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0) std::swap(kx, ky);  // keep the winding
    const double sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1 / d[kz];
    const dvec3 a = v0 - ray.origin, b = v1 - ray.origin, c = v2 - ray.origin;
    const double ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
    const double bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
    const double cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];
    const double eu = cx * by - cy * bx;  // weight of v0
    const double ev = ax * cy - ay * cx;  // weight of v1
    const double ew = bx * ay - by * ax;  // weight of v2
    if ((eu < 0 || ev < 0 || ew < 0) && (eu > 0 || ev > 0 || ew > 0)) return std::nullopt;
    const double det = eu + ev + ew;
    if (det == 0) return std::nullopt;
    const double az = sz * a[kz], bz = sz * b[kz], cz = sz * c[kz];
    const double tScaled = eu * az + ev * bz + ew * cz;
    const double t = tScaled / det;
    double dt = 0;
    if (conservative) {
        const double maxZ = std::max({std::abs(az), std::abs(bz), std::abs(cz)});
        const double maxX = std::max({std::abs(ax), std::abs(bx), std::abs(cx)});
        const double maxY = std::max({std::abs(ay), std::abs(by), std::abs(cy)});
        const double deltaZ = gamma(3) * maxZ;
        const double deltaX = gamma(5) * (maxX + maxZ), deltaY = gamma(5) * (maxY + maxZ);
        const double deltaE = 2 * (gamma(2) * maxX * maxY + deltaY * maxX + deltaX * maxY);
        const double maxE = std::max({std::abs(eu), std::abs(ev), std::abs(ew)});
        dt = 3 * (gamma(3) * maxE * maxZ + deltaE * maxZ + deltaZ * maxE) / std::abs(det);
    }
    if (!(t > dt)) return std::nullopt;
    return TriangleHit{t, ev / det, ew / det};
}

// Section 2, planes: n.o is off by up to gamma(4) (|offset| + |n|.|o|), inside which the origin
// is on the plane and no t is trusted.
std::optional<double> intersectPlane(const Ray& ray, dvec3 n, double offset, bool conservative) {
    const double den = glm::dot(n, ray.dir);
    if (den == 0) return std::nullopt;
    const double num = offset - glm::dot(n, ray.origin);
    if (conservative && !(std::abs(num) > gamma(4) * (std::abs(offset) +
                                                      glm::dot(glm::abs(n), glm::abs(ray.origin)))))
        return std::nullopt;
    const double t = num / den;
    if (t > 0) return t;
    return std::nullopt;
}

dvec3 reflect(dvec3 d, dvec3 n) { return d - 2.0 * n * glm::dot(d, n); }

// Section 6, Algorithm 1 with the report's TIR test and last line fixed.
std::optional<dvec3> refract(dvec3 d, dvec3 n, double eta) {
    const double c = -glm::dot(n, d);
    const double s = eta * eta * (1 - c * c);
    if (s > 1) return std::nullopt;
    const double t = std::sqrt(1 - s);
    return eta * d + (eta * c - t) * n;
}

// Section 7, Algorithm 5 with the square root fixed.
double fresnel(double cosI, double n1, double n2) {
    const double sinT = (n1 / n2) * std::sqrt(std::max(0.0, 1 - cosI * cosI));
    if (sinT >= 1) return 1;
    const double cosT = std::sqrt(1 - sinT * sinT);
    const double rs = (n2 * cosI - n1 * cosT) / (n2 * cosI + n1 * cosT);
    const double rp = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    return (rs * rs + rp * rp) / 2;
}

}  // namespace rt::ref
