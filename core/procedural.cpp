// rtlab — core/cl/procedural.cl in double precision (see core/procedural.h). Kept line for line
// with the OpenCL file so that a change to one is easy to mirror in the other.
#include "core/procedural.h"

#include <algorithm>
#include <cmath>

namespace rt::proc {

uint32_t hash(int x, int y, int z) {
    uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ uint32_t(z) * 0xcb1ab31fu;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

double grad(uint32_t h, double x, double y, double z) {
    h &= 15u;
    const double u = h < 8u ? x : y;
    const double v = h < 4u ? y : (h == 12u || h == 14u ? x : z);
    return ((h & 1u) ? -u : u) + ((h & 2u) ? -v : v);
}

double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

double noise(glm::dvec3 p) {
    const glm::dvec3 f = glm::floor(p);
    const int x = int(f.x), y = int(f.y), z = int(f.z);
    const glm::dvec3 d = p - f;
    const double u = fade(d.x), v = fade(d.y), w = fade(d.z);
    const double n000 = grad(hash(x, y, z), d.x, d.y, d.z);
    const double n100 = grad(hash(x + 1, y, z), d.x - 1, d.y, d.z);
    const double n010 = grad(hash(x, y + 1, z), d.x, d.y - 1, d.z);
    const double n110 = grad(hash(x + 1, y + 1, z), d.x - 1, d.y - 1, d.z);
    const double n001 = grad(hash(x, y, z + 1), d.x, d.y, d.z - 1);
    const double n101 = grad(hash(x + 1, y, z + 1), d.x - 1, d.y, d.z - 1);
    const double n011 = grad(hash(x, y + 1, z + 1), d.x, d.y - 1, d.z - 1);
    const double n111 = grad(hash(x + 1, y + 1, z + 1), d.x - 1, d.y - 1, d.z - 1);
    const double x00 = n000 + u * (n100 - n000), x10 = n010 + u * (n110 - n010);
    const double x01 = n001 + u * (n101 - n001), x11 = n011 + u * (n111 - n011);
    const double y0 = x00 + v * (x10 - x00), y1 = x01 + v * (x11 - x01);
    return y0 + w * (y1 - y0);
}

double fbm(glm::dvec3 p, int octaves, bool turbulence) {
    double sum = 0, amp = 1;
    for (int i = 0; i < octaves; ++i) {
        const double n = noise(p);
        sum += amp * (turbulence ? std::fabs(n) : n);
        p *= 2.0;
        p -= 65536.0 * glm::round(p / 65536.0);  // as procedural.cl: no int overflow at 64 octaves
        amp *= 0.5;
    }
    return sum;
}

double pattern(int pattern, glm::dvec3 p, int octaves) {
    if (pattern == RT_PATTERN_CHECKER) {
        const glm::dvec3 f = glm::floor(p);
        return ((int(f.x) + int(f.y) + int(f.z)) & 1) ? 1.0 : 0.0;
    }
    if (pattern == RT_PATTERN_MARBLE) return 0.5 + 0.5 * std::sin(p.x + 5 * fbm(p, octaves, true));
    if (pattern == RT_PATTERN_WOOD) {
        const double r = std::sqrt(p.x * p.x + p.z * p.z) + 0.5 * fbm(p, octaves, false);
        return 0.5 + 0.5 * std::sin(6.2831853 * r);
    }
    if (pattern == RT_PATTERN_GRANITE)
        return std::clamp(0.5 + 1.5 * fbm(p, octaves, false), 0.0, 1.0);
    return 0;
}

glm::dvec3 bump(glm::dvec3 p, glm::dvec3 n, int octaves, double strength) {
    const double h = 0.015625;
    const double f0 = fbm(p, octaves, false);
    glm::dvec3 g(fbm(p + glm::dvec3(h, 0, 0), octaves, false) - f0,
                 fbm(p + glm::dvec3(0, h, 0), octaves, false) - f0,
                 fbm(p + glm::dvec3(0, 0, h), octaves, false) - f0);
    g /= h;
    g -= glm::dot(g, n) * n;
    return glm::normalize(n - strength * g);
}

void apply(const dev::Material& m, glm::dvec3 p, glm::dvec3& diffuse, glm::dvec3& n) {
    const glm::dvec3 q = p * double(m.patternScale);
    if (m.pattern == RT_PATTERN_BUMP) {
        n = bump(q, n, m.octaves, m.bump);
        return;
    }
    const double t = pattern(m.pattern, q, m.octaves);
    const glm::dvec3 second(m.diffuse2.x, m.diffuse2.y, m.diffuse2.z);
    diffuse = diffuse + t * (second - diffuse);
}

}  // namespace rt::proc
