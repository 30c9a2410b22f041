// rtlab — traversal of the 4-wide BVH of --accel wide (issue 18; built by core/accel_wide.cpp).
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
inline float Wide_Step(uint e) { return as_float(e << 23); }

// A node as four 16-byte loads (the buffer and its 64-byte records are 16-byte aligned). Read
// member by member, its byte arrays would be fetched a byte at a time on a GPU, where an
// unaligned word load does not exist: about 40 loads per node. The words, in WideNode's order
// (little-endian, as the host that wrote them):
//   w0: origin.x, origin.y, origin.z, exponent[0..2] | sphereMask << 24
//   w1: loX[0..3], loY[0..3], loZ[0..3], hiX[0..3]
//   w2: hiY[0..3], hiZ[0..3], child[0], child[1]
//   w3: child[2], child[3], count[0] | count[1] << 16, count[2] | count[3] << 16
typedef struct WideWords {
    uint4 w0, w1, w2, w3;
} WideWords;

inline WideWords Wide_Load(global const WideNode* nodes, int index) {
    global const uint4* p = (global const uint4*)(nodes + index);
    WideWords n;
    n.w0 = p[0];
    n.w1 = p[1];
    n.w2 = p[2];
    n.w3 = p[3];
    return n;
}

inline float4 Wide_Bytes(uint word) { return convert_float4(as_uchar4(word)); }

// Entry distances of the four children's boxes; INFINITY where the ray does not enter the box
// before tMax, or the slot is empty. The decoded bound origin + q * step is exact in q * step,
// so mad() and the host's arithmetic agree up to the rounding of one addition; the boxes are
// padded far beyond that (core/accel.cpp kPad).
inline float4 Wide_Enter(const WideWords* n, float3 rayOrigin, float3 inv, float tMax) {
    uint e = n->w0.w;
    float3 step = (float3)(Wide_Step(e & 0xffu), Wide_Step((e >> 8) & 0xffu),
                           Wide_Step((e >> 16) & 0xffu));
    float3 a = (as_float3(n->w0.xyz) - rayOrigin) * inv;
    float3 b = step * inv;
    float4 x0 = mad(Wide_Bytes(n->w1.x), b.x, a.x);
    float4 x1 = mad(Wide_Bytes(n->w1.w), b.x, a.x);
    float4 y0 = mad(Wide_Bytes(n->w1.y), b.y, a.y);
    float4 y1 = mad(Wide_Bytes(n->w2.x), b.y, a.y);
    float4 z0 = mad(Wide_Bytes(n->w1.z), b.z, a.z);
    float4 z1 = mad(Wide_Bytes(n->w2.y), b.z, a.z);
    float4 enter = fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmax(fmin(z0, z1), 0.0f));
    float4 leave = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmin(fmax(z0, z1), tMax));
    int4 child = as_int4((uint4)(n->w2.zw, n->w3.xy));
    return select((float4)(INFINITY), enter, (enter <= leave) & (child != (int4)(-1)));
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
        WideWords n = Wide_Load(nodes, index);
        float t[4];
        vstore4(Wide_Enter(&n, ray.origin, inv, hit->t), 0, t);
        int child[4] = {as_int(n.w2.z), as_int(n.w2.w), as_int(n.w3.x), as_int(n.w3.y)};
        uint count[4] = {n.w3.z & 0xffffu, n.w3.z >> 16, n.w3.w & 0xffffu, n.w3.w >> 16};
        uint sphereMask = n.w0.w >> 24;
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
