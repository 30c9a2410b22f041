// rtlab — procedural materials: 3D gradient noise, fBm and turbulence, and the
// patterns built on them (checker, marble, wood, granite, bump). They exist to give shading a
// cost knob (Material.octaves) and to give neighbouring rays different code paths, the setting
// in which Laine, Karras and Aila (2013) found the wavefront ahead of the megakernel.
// Compiled only when a scene uses a pattern (RT_HAS_PROCEDURAL). core/reference.cpp implements
// the same definitions in double precision; core/SHADING.md section 5 states them.
#ifndef RTLAB_CL_PROCEDURAL
#define RTLAB_CL_PROCEDURAL

// Integer hash of a lattice point (a multiply-xorshift mix): the same 32-bit arithmetic on the
// host, so the CPU reference picks the same gradients.
inline uint Procedural_Hash(int x, int y, int z) {
    uint h = (uint)x * 0x8da6b343u ^ (uint)y * 0xd8163841u ^ (uint)z * 0xcb1ab31fu;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

// Dot product of the offset (x, y, z) with one of 12 cube-edge gradients (Perlin 2002), picked
// by the low 4 bits of the hash (16 entries, 4 of them repeated).
inline float Procedural_Grad(uint h, float x, float y, float z) {
    h &= 15u;
    float u = h < 8u ? x : y;
    float v = h < 4u ? y : (h == 12u || h == 14u ? x : z);
    return ((h & 1u) ? -u : u) + ((h & 2u) ? -v : v);
}

// 6t^5 - 15t^4 + 10t^3: zero first and second derivative at the lattice.
inline float Procedural_Fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

// Gradient noise, 0 at every lattice point, within about [-1, 1].
inline float Procedural_Noise(float3 p) {
    float3 f = floor(p);
    int x = (int)f.x, y = (int)f.y, z = (int)f.z;
    float3 d = p - f;
    float u = Procedural_Fade(d.x), v = Procedural_Fade(d.y), w = Procedural_Fade(d.z);
    float n000 = Procedural_Grad(Procedural_Hash(x, y, z), d.x, d.y, d.z);
    float n100 = Procedural_Grad(Procedural_Hash(x + 1, y, z), d.x - 1.0f, d.y, d.z);
    float n010 = Procedural_Grad(Procedural_Hash(x, y + 1, z), d.x, d.y - 1.0f, d.z);
    float n110 = Procedural_Grad(Procedural_Hash(x + 1, y + 1, z), d.x - 1.0f, d.y - 1.0f, d.z);
    float n001 = Procedural_Grad(Procedural_Hash(x, y, z + 1), d.x, d.y, d.z - 1.0f);
    float n101 = Procedural_Grad(Procedural_Hash(x + 1, y, z + 1), d.x - 1.0f, d.y, d.z - 1.0f);
    float n011 = Procedural_Grad(Procedural_Hash(x, y + 1, z + 1), d.x, d.y - 1.0f, d.z - 1.0f);
    float n111 =
        Procedural_Grad(Procedural_Hash(x + 1, y + 1, z + 1), d.x - 1.0f, d.y - 1.0f, d.z - 1.0f);
    float x00 = n000 + u * (n100 - n000), x10 = n010 + u * (n110 - n010);
    float x01 = n001 + u * (n101 - n001), x11 = n011 + u * (n111 - n011);
    float y0 = x00 + v * (x10 - x00), y1 = x01 + v * (x11 - x01);
    return y0 + w * (y1 - y0);
}

// Sum of `octaves` noise layers, each at twice the frequency and half the amplitude; turbulence
// sums their absolute values (the creases marble needs). 0 octaves: 0, no work. Past 2^15 a
// coordinate wraps by 2^16 (identity below), so that 64 octaves never overflow the lattice's int;
// those octaves weigh 2^-12 or less, so float and double may round the wrap differently unseen.
inline float Procedural_Fbm(float3 p, int octaves, bool turbulence) {
    float sum = 0.0f, amp = 1.0f;
    for (int i = 0; i < octaves; ++i) {
        float n = Procedural_Noise(p);
        sum += amp * (turbulence ? fabs(n) : n);
        p = p * 2.0f;
        p = p - 65536.0f * round(p / 65536.0f);
        amp *= 0.5f;
    }
    return sum;
}

// The pattern value in [0, 1] at object-space point p (already scaled): how far D moves toward
// the second colour.
inline float Procedural_Pattern(int pattern, float3 p, int octaves) {
    if (pattern == RT_PATTERN_CHECKER) {
        float3 f = floor(p);
        return (((int)f.x + (int)f.y + (int)f.z) & 1) ? 1.0f : 0.0f;
    }
    if (pattern == RT_PATTERN_MARBLE)
        return 0.5f + 0.5f * sin(p.x + 5.0f * Procedural_Fbm(p, octaves, true));
    if (pattern == RT_PATTERN_WOOD) {
        float r = sqrt(p.x * p.x + p.z * p.z) + 0.5f * Procedural_Fbm(p, octaves, false);
        return 0.5f + 0.5f * sin(6.2831853f * r);
    }
    if (pattern == RT_PATTERN_GRANITE)
        return clamp(0.5f + 1.5f * Procedural_Fbm(p, octaves, false), 0.0f, 1.0f);
    return 0.0f;
}

// Bump: the shading normal tilted against the fBm gradient (forward differences, step 1/64 of
// a lattice cell), its component along n removed so that only the tilt remains.
inline float3 Procedural_Bump(float3 p, float3 n, int octaves, float strength) {
    const float h = 0.015625f;
    float f0 = Procedural_Fbm(p, octaves, false);
    float3 g = (float3)(Procedural_Fbm(p + (float3)(h, 0.0f, 0.0f), octaves, false) - f0,
                        Procedural_Fbm(p + (float3)(0.0f, h, 0.0f), octaves, false) - f0,
                        Procedural_Fbm(p + (float3)(0.0f, 0.0f, h), octaves, false) - f0) /
               h;
    g = g - dot(g, n) * n;
    return normalize(n - strength * g);
}

// Shade_Base's hook: the diffuse colour and shading normal of material m, whose pattern is
// `pattern` (m->pattern, or the same as a constant), at hit point p.
RT_PATTERN_LINKAGE void Procedural_Apply(const Material* m, int pattern, float3 p, float3* diffuse,
                                         float3* n) {
    float3 q = p * m->patternScale;
    if (pattern == RT_PATTERN_BUMP) {
        *n = Procedural_Bump(q, *n, m->octaves, m->bump);
        return;
    }
    float t = Procedural_Pattern(pattern, q, m->octaves);
    *diffuse = *diffuse + t * (f3(m->diffuse2) - *diffuse);
}

#endif
