// rtlab — traversal of the 4-wide BVH of --accel wide (built by core/accel_wide.cpp).
// One node load gives the quantised boxes of four children, tested together as float4 slabs.
// Leaf children are intersected at once; inner children the ray enters before the current hit
// are ordered by entry distance, the nearest visited next and the others deferred on a short
// stack with their entry distance, so that a deferred node is dropped once a nearer hit exists.
// Included by accel.cl; the nodes travel in the bvh buffer of SceneData.
#ifndef RTLAB_CL_ACCEL_WIDE
#define RTLAB_CL_ACCEL_WIDE

// The builder bounds the deferred entries on every path by this (core/accel_wide.cpp kStack).
#define RT_WIDE_STACK 64

// 2^(e - 127): the exponent bits of a float.
inline float Wide_Step(uchar e) { return as_float((uint)e << 23); }

// Entry distances of the four children's boxes; INFINITY where the ray does not enter the box
// before tMax, or the slot is empty. The decoded bound origin + q * step is exact in q * step,
// so mad() and the host's arithmetic agree up to the rounding of one addition; the boxes are
// padded far beyond that (core/accel.cpp kPad).
inline float4 Wide_Enter(global const WideNode* n, float3 rayOrigin, float3 inv, float tMax) {
    float3 step =
        (float3)(Wide_Step(n->exponent[0]), Wide_Step(n->exponent[1]), Wide_Step(n->exponent[2]));
    float3 a = (f3(n->origin) - rayOrigin) * inv;
    float3 b = step * inv;
    float4 x0 = mad(convert_float4(vload4(0, n->loX)), b.x, a.x);
    float4 x1 = mad(convert_float4(vload4(0, n->hiX)), b.x, a.x);
    float4 y0 = mad(convert_float4(vload4(0, n->loY)), b.y, a.y);
    float4 y1 = mad(convert_float4(vload4(0, n->hiY)), b.y, a.y);
    float4 z0 = mad(convert_float4(vload4(0, n->loZ)), b.z, a.z);
    float4 z1 = mad(convert_float4(vload4(0, n->hiZ)), b.z, a.z);
    float4 enter = fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmax(fmin(z0, z1), 0.0f));
    float4 leave = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmin(fmax(z0, z1), tMax));
    int4 used = vload4(0, n->child) != (int4)(-1);
    return select((float4)(INFINITY), enter, (enter <= leave) & used);
}

inline bool Wide_Leaf(const SceneData* sc, int first, int count, bool spheres, Ray ray, Hit* hit,
                      bool anyHit) {
    bool found = false;
#ifdef RT_HAS_SPHERES
    if (spheres) {
        for (int i = first; i < first + count; ++i)
            if (Hit_Sphere(sc, i, ray, hit)) {
                found = true;
                if (anyHit) return true;
            }
    }
#endif
#ifdef RT_HAS_TRIANGLES
    if (!spheres) {
        for (int i = first; i < first + count; ++i)
            if (Hit_Triangle(sc, i, ray, hit)) {
                found = true;
                if (anyHit) return true;
            }
    }
#endif
    return found;
}

inline bool Wide_Query(const SceneData* sc, Ray ray, Hit* hit, bool anyHit) {
    global const WideNode* nodes = (global const WideNode*)sc->bvh;
    float3 inv = Ray_InvDir(ray.dir);
    int stack[RT_WIDE_STACK];
    float stackT[RT_WIDE_STACK];  // entry distance of each deferred node
    int top = 0, index = 0;
    bool found = false;
    for (;;) {
        global const WideNode* n = nodes + index;
        float t[4];
        vstore4(Wide_Enter(n, ray.origin, inv, hit->t), 0, t);
        int child[4];
        vstore4(vload4(0, n->child), 0, child);
        ushort count[4];
        vstore4(vload4(0, n->count), 0, count);
        uint sphereMask = n->sphereMask;
        // Leaves first: a hit there shortens the ray before the inner children are ordered.
        for (int k = 0; k < 4; ++k) {
            if (count[k] == 0 || !(t[k] < hit->t)) continue;
            if (Wide_Leaf(sc, child[k], count[k], (sphereMask >> k) & 1u, ray, hit, anyHit)) {
                found = true;
                if (anyHit) return true;
            }
        }
        // Inner children the ray enters before the hit, nearest first (insertion sort of <= 4).
        int near[4];
        float nearT[4];
        int m = 0;
        for (int k = 0; k < 4; ++k) {
            if (count[k] != 0 || !(t[k] < hit->t)) continue;
            int j = m++;
            while (j > 0 && nearT[j - 1] > t[k]) {
                near[j] = near[j - 1];
                nearT[j] = nearT[j - 1];
                --j;
            }
            near[j] = child[k];
            nearT[j] = t[k];
        }
        if (m > 0) {
            for (int j = m - 1; j > 0; --j) {
                stack[top] = near[j];
                stackT[top] = nearT[j];
                ++top;
            }
            index = near[0];
            continue;
        }
        // Next: the most recently deferred node the ray enters before the current best hit.
        while (top > 0 && !(stackT[top - 1] < hit->t)) --top;
        if (top == 0) return found;
        index = stack[--top];
    }
}

#endif
