// rtlab — traversal of the compressed 8-wide BVH of --accel cwbvh (built by
// core/accel_cwbvh.cpp; the scheme of Ylitie, Karras and Laine 2017). One node is five 16-byte
// loads holding the quantised boxes of eight children, tested together as float8 slabs. The
// children a ray enters become a group: a mask of slots in the ray's visit order (no sorting:
// the builder puts each child in the slot of the corner it lies towards) and the base index of
// the node's inner children. The walk takes the group's next child; the rest of the group waits
// on the stack as one entry while the child's subtree is walked. A node's leaves are tested as
// soon as the node is, from its entries of CwbvhPrim laid out side by side. Included by
// accel.cl; the nodes travel in the bvh buffer of SceneData, the leaf entries in its cells buffer.
#ifndef RTLAB_CL_ACCEL_CWBVH
#define RTLAB_CL_ACCEL_CWBVH

// Deferred groups on any path stay below this (checked by checkCwbvh, core/accel_cwbvh.cpp).
#define RT_CWBVH_STACK 64

// Index of the lowest set bit of a nonzero mask (OpenCL C 1.2 has clz but not ctz).
inline uint Cwbvh_Lowest(uint m) { return 31u - clz(m & (0u - m)); }

// Bit s of a slot mask moved to bit s ^ octant: the order in which a ray of that octant visits
// the slots, nearest corner first.
inline uint Cwbvh_VisitOrder(uint m, uint octant) {
    m = (octant & 1u) ? ((m & 0x55u) << 1) | ((m >> 1) & 0x55u) : m;
    m = (octant & 2u) ? ((m & 0x33u) << 2) | ((m >> 2) & 0x33u) : m;
    m = (octant & 4u) ? ((m & 0x0Fu) << 4) | ((m >> 4) & 0x0Fu) : m;
    return m;
}

// The slots whose boxes the ray enters before tMax, as bits. Per axis the bounds facing the ray
// (the lo bytes, or the hi bytes where it runs towards -axis) give the entry distances and the
// others the exit ones, so an empty slot (lo 255, hi 0) is never entered. Each distance is one
// fma of the byte: q * (step / d) + (origin - o) / d, exact in q * step as in Wide_Enter.
inline uint Cwbvh_Enter(float4 w0, float4 w2, float4 w3, float4 w4, float3 rayOrigin, float3 inv,
                        float tMax) {
    uint head = as_uint(w0.w);
    float3 step = (float3)(as_float((head & 0xFFu) << 23), as_float(((head >> 8) & 0xFFu) << 23),
                           as_float(((head >> 16) & 0xFFu) << 23));
    float3 scale = step * inv, offset = (w0.xyz - rayOrigin) * inv;
    uint2 loX = as_uint2(w2.xy), loY = as_uint2(w2.zw), loZ = as_uint2(w3.xy);
    uint2 hiX = as_uint2(w3.zw), hiY = as_uint2(w4.xy), hiZ = as_uint2(w4.zw);
    float8 nx = fma(convert_float8(as_uchar8(inv.x < 0.0f ? hiX : loX)), (float8)(scale.x),
                    (float8)(offset.x));
    float8 fx = fma(convert_float8(as_uchar8(inv.x < 0.0f ? loX : hiX)), (float8)(scale.x),
                    (float8)(offset.x));
    float8 ny = fma(convert_float8(as_uchar8(inv.y < 0.0f ? hiY : loY)), (float8)(scale.y),
                    (float8)(offset.y));
    float8 fy = fma(convert_float8(as_uchar8(inv.y < 0.0f ? loY : hiY)), (float8)(scale.y),
                    (float8)(offset.y));
    float8 nz = fma(convert_float8(as_uchar8(inv.z < 0.0f ? hiZ : loZ)), (float8)(scale.z),
                    (float8)(offset.z));
    float8 fz = fma(convert_float8(as_uchar8(inv.z < 0.0f ? loZ : hiZ)), (float8)(scale.z),
                    (float8)(offset.z));
    float8 enter = fmax(fmax(nx, ny), fmax(nz, (float8)(0.0f)));
    float8 leave = fmin(fmin(fx, fy), fmin(fz, (float8)(tMax)));
    int8 bits = (enter <= leave) & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
    int4 b4 = bits.lo | bits.hi;
    int2 b2 = b4.lo | b4.hi;
    return (uint)(b2.x | b2.y);
}

// The leaf entries of the given leaf slots: bit i for prims[primBase + i].
inline uint Cwbvh_LeafEntries(uint leafSlots, uint2 meta) {
    uint entries = 0;
    while (leafSlots != 0) {
        uint s = Cwbvh_Lowest(leafSlots);
        leafSlots &= leafSlots - 1u;
        uint m = ((s < 4u ? meta.x : meta.y) >> (8u * (s & 3u))) & 0xFFu;
        entries |= ((2u << (m >> 5)) - 1u) << (m & 31u);
    }
    return entries;
}

// Leaf entry e: a triangle (its vertices in the entry) or a sphere; true when it becomes the hit.
inline bool Cwbvh_Prim(const SceneData* sc, global const float4* prims, int e, Ray ray, Hit* hit) {
    global const float4* q = prims + 3 * e;
    float4 a = q[0];
    int ref = as_int(a.w);
#ifdef RT_HAS_SPHERES
    if (ref < 0) return Hit_Sphere(sc, ~ref, ray, hit);
#endif
#ifdef RT_HAS_TRIANGLES
    float4 b = q[1], c = q[2];
    return Hit_TriangleWith(a.xyz, b.xyz, c.xyz, ref, ray, hit);
#else
    return false;
#endif
}

inline bool Cwbvh_Query(const SceneData* sc, Ray ray, Hit* hit, bool anyHit) {
    global const float4* nodes = (global const float4*)sc->bvh;
    global const float4* prims = (global const float4*)sc->cells;
    float3 inv = Ray_InvDir(ray.dir);
    uint octant = (inv.x < 0.0f ? 1u : 0u) | (inv.y < 0.0f ? 2u : 0u) | (inv.z < 0.0f ? 4u : 0u);
    uint2 stack[RT_CWBVH_STACK];  // deferred groups: (base, bits) as below
    int top = 0;
    // The current group: its inner children are nodes base, base + 1, ... in slot order; bits
    // 0-7 are the slots still to visit, in visit order, and bits 8-15 the node's inner slots.
    uint groupBase = 0, groupBits = 0;
    int node = 0;
    bool found = false;
    for (;;) {
        global const float4* p = nodes + 5 * node;
        float4 w0 = p[0], w1 = p[1], w2 = p[2], w3 = p[3], w4 = p[4];
        uint slots = Cwbvh_Enter(w0, w2, w3, w4, ray.origin, inv, hit->t);
        uint innerMask = as_uint(w0.w) >> 24;
        uint entries = Cwbvh_LeafEntries(slots & ~innerMask, as_uint2(w1.zw));
        int primBase = as_int(w1.y);
        while (entries != 0) {
            int e = primBase + (int)Cwbvh_Lowest(entries);
            entries &= entries - 1u;
            if (Cwbvh_Prim(sc, prims, e, ray, hit)) {
                found = true;
                if (anyHit) return true;
            }
        }
        uint visit = Cwbvh_VisitOrder(slots & innerMask, octant);
        if (visit != 0) {
            if ((groupBits & 0xFFu) != 0) stack[top++] = (uint2)(groupBase, groupBits);
            groupBase = as_uint(w1.x);
            groupBits = visit | innerMask << 8;
        }
        if ((groupBits & 0xFFu) == 0) {
            if (top == 0) return found;
            uint2 g = stack[--top];
            groupBase = g.x;
            groupBits = g.y;
        }
        uint k = Cwbvh_Lowest(groupBits & 0xFFu);
        groupBits &= ~(1u << k);
        uint slot = k ^ octant;
        node = (int)(groupBase + popcount((groupBits >> 8) & ((1u << slot) - 1u)));
    }
}

#endif
