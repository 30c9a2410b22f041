// rtlab — the procedural materials of core/cl/procedural.cl in double precision, for the CPU
// reference (the accuracy oracle) and the unit tests. Same lattice hash, gradients, fade curve,
// octave sums and patterns; only the float arithmetic becomes double.
#ifndef RTLAB_CORE_PROCEDURAL_H
#define RTLAB_CORE_PROCEDURAL_H

#include <cstdint>
#include <glm/glm.hpp>

#include "core/types.h"

namespace rt::proc {

uint32_t hash(int x, int y, int z);
double grad(uint32_t h, double x, double y, double z);
double fade(double t);
double noise(glm::dvec3 p);
double fbm(glm::dvec3 p, int octaves, bool turbulence);
double pattern(int pattern, glm::dvec3 p, int octaves);
glm::dvec3 bump(glm::dvec3 p, glm::dvec3 n, int octaves, double strength);
// The diffuse colour and shading normal of material m at hit point p (pattern != 0).
void apply(const dev::Material& m, glm::dvec3 p, glm::dvec3& diffuse, glm::dvec3& n);

}  // namespace rt::proc

#endif
