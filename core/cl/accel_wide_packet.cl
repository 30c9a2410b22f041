// rtlab — packet traversal of the 4-wide BVH (--accel wide) for CPU devices.
// PoCL runs one work-item per core at a time and cannot vectorize Wide_Query's loop across
// work-items, so a single ray uses at most four SIMD lanes (the children of a node). Here one
// work-item traces RT_PACKET consecutive rays (8 or 16; the caller orders them in 8x8 tiles, so
// they are coherent) in structure-of-arrays form, one OpenCL vector per ray component, which
// PoCL compiles to AVX/AVX-512 registers: each node load gives the entry distances of its four
// children for every ray of the packet, and each triangle load is tested against every ray.
//
// Traversal (closest hit, or any hit for shadow rays):
// - a child is visited when some live ray enters it before that ray's own current hit;
// - leaf children first, their triangles tested for all rays at once with the arithmetic of
//   Triangle_Intersect (core/cl/intersect.cl), each ray keeping its closest t;
// - inner children ordered by the packet's smallest entry distance, the nearest visited next,
//   the others deferred on a short stack with every ray's entry distance, so that a deferred
//   node is skipped once no ray would enter it before its current hit;
// - a shadow ray retires when it is occluded; the packet stops when all have.
// A ray's result does not depend on the order: every triangle it could hit below its current
// hit is tested, with the same per-ray arithmetic as the single-ray query, so the closest t is
// the same float, and a shadow ray is occluded exactly when Wide_Query says so.
// Each ray gets the whole hit Scene_Intersect would give it (PacketHit: t, kind, object and a
// triangle's uv), so a pipeline stage can shade from it (wavefront/queue/queue_packet.cl).
// Triangles with Triangle_Intersect's test (the watertight one under RT_WATERTIGHT, else
// Moller-Trumbore); spheres in a leaf (RT_HAS_SPHERES) are tested ray by ray with Hit_Sphere.
// Planes are the caller's: Scene_Query tests them before the BVH, so the caller does too and
// passes their hit in. Included by trace_rays.cl and queue_packet.cl after scene.cl
// (RT_ACCEL_WIDE); reuses Wide_Step and RT_WIDE_STACK.
#ifndef RTLAB_CL_ACCEL_WIDE_PACKET
#define RTLAB_CL_ACCEL_WIDE_PACKET

#ifndef RT_PACKET
#define RT_PACKET 16
#endif
#if RT_PACKET == 16
typedef float16 floatP;
typedef int16 intP;
#define vloadP vload16
#define vstoreP vstore16
#elif RT_PACKET == 8
typedef float8 floatP;
typedef int8 intP;
#define vloadP vload8
#define vstoreP vstore8
#else
#error "RT_PACKET must be 8 or 16"
#endif

// A packet of rays, one vector per component; i is Ray_InvDir's 1/d per ray. With
// RT_WATERTIGHT, also each ray's shear of Triangle_Intersect (Woop, Benthin and Wald): the
// axes kx, ky, kz as masks (k == 1, k == 2; axis 0 is neither), sx, sy, sz (Packet_Shear).
typedef struct RayPacket {
    floatP ox, oy, oz;
    floatP dx, dy, dz;
    floatP ix, iy, iz;
#ifdef RT_WATERTIGHT
    intP kx1, kx2, ky1, ky2, kz1, kz2;
    floatP sx, sy, sz;
    floatP okx, oky, okz;  // the origin on axes kx, ky, kz
    int kx, ky, kz;        // the axes when every ray has the same, else kx = -1
#endif
} RayPacket;

// Every ray's hit as Scene_Query keeps it: t is the ray's tMax on entry (-INFINITY for an
// unused lane) and its closest hit on return; kind RT_KIND_MISS until something is hit; u, v
// a triangle's barycentrics (Hit.uv). For any-hit queries t drops to 0 when a ray is occluded.
typedef struct PacketHit {
    floatP t, u, v;
    intP kind, object;
} PacketHit;

inline PacketHit PacketHit_Make(floatP tMax) {
    PacketHit h;
    h.t = tMax;
    h.u = (floatP)(0.0f);
    h.v = (floatP)(0.0f);
    h.kind = (intP)(RT_KIND_MISS);
    h.object = (intP)(-1);
    return h;
}

// Component k of (x, y, z) in each lane, k given as the masks k == 1 and k == 2.
inline floatP Packet_Component(floatP x, floatP y, floatP z, intP k1, intP k2) {
    return select(select(x, y, k1), z, k2);
}

inline floatP Packet_InvDir(floatP d) {
    floatP tiny = copysign((floatP)(1e-20f), d);
    return 1.0f / select(d, tiny, fabs(d) < (floatP)(1e-20f));
}

// Whether some lane is set: an OR of halves and one test. PoCL's any() tests the lanes one
// pair at a time, a chain of branches that the CPU mispredicts.
inline bool Packet_Any(intP m) {
#if RT_PACKET == 16
    int8 a = m.lo | m.hi;
#else
    int8 a = m;
#endif
    int4 b = a.lo | a.hi;
    int2 c = b.lo | b.hi;
    return (c.x | c.y) < 0;
}

// Smallest and largest lane, by halving (no NaN fix-ups: the inputs are never NaN).
inline float Packet_Smallest(floatP v) {
#if RT_PACKET == 16
    float8 a = select(v.hi, v.lo, v.lo < v.hi);
#else
    float8 a = v;
#endif
    float4 b = select(a.hi, a.lo, a.lo < a.hi);
    float2 c = select(b.hi, b.lo, b.lo < b.hi);
    return c.x < c.y ? c.x : c.y;
}

inline float Packet_Largest(floatP v) {
#if RT_PACKET == 16
    float8 a = select(v.hi, v.lo, v.lo > v.hi);
#else
    float8 a = v;
#endif
    float4 b = select(a.hi, a.lo, a.lo > a.hi);
    float2 c = select(b.hi, b.lo, b.lo > b.hi);
    return c.x > c.y ? c.x : c.y;
}

// A node's slab distances for every ray, t = q * scale + base on each axis, with its quantised
// child bounds q converted once per node (four children at a time).
typedef struct PacketSlabs {
    floatP baseX, baseY, baseZ;
    floatP scaleX, scaleY, scaleZ;
    float lo[3][4], hi[3][4];  // [axis][child]
} PacketSlabs;

inline PacketSlabs Packet_Slabs(global const WideNode* n, const RayPacket* r) {
    PacketSlabs s;
    s.baseX = (n->origin.x - r->ox) * r->ix;
    s.baseY = (n->origin.y - r->oy) * r->iy;
    s.baseZ = (n->origin.z - r->oz) * r->iz;
    s.scaleX = Wide_Step(n->exponent[0]) * r->ix;
    s.scaleY = Wide_Step(n->exponent[1]) * r->iy;
    s.scaleZ = Wide_Step(n->exponent[2]) * r->iz;
    vstore4(convert_float4(vload4(0, n->loX)), 0, s.lo[0]);
    vstore4(convert_float4(vload4(0, n->loY)), 0, s.lo[1]);
    vstore4(convert_float4(vload4(0, n->loZ)), 0, s.lo[2]);
    vstore4(convert_float4(vload4(0, n->hiX)), 0, s.hi[0]);
    vstore4(convert_float4(vload4(0, n->hiY)), 0, s.hi[1]);
    vstore4(convert_float4(vload4(0, n->hiZ)), 0, s.hi[2]);
    return s;
}

// Minimum and maximum as compare-and-select (Min3_Fast in accel.cl): one instruction each,
// where fmin/fmax add a NaN fix-up. No slab distance is NaN (Packet_InvDir keeps 1/d finite).
inline floatP Lanes_Min(floatP a, floatP b) { return select(b, a, a < b); }
inline floatP Lanes_Max(floatP a, floatP b) { return select(b, a, a > b); }

// Entry distance of child k (lo and hi: its quantised bounds) for every ray, INFINITY where the
// ray does not enter its box before its current hit (Wide_Enter's test, then Wide_Query's
// t < hit). fma, where Wide_Enter has mad: the boxes are padded far beyond either's rounding,
// so this decides only which nodes are visited, never a ray's hit.
inline floatP Packet_Enter(const PacketSlabs* s, float loX, float loY, float loZ, float hiX,
                           float hiY, float hiZ, floatP hitT) {
    floatP x0 = fma((floatP)(loX), s->scaleX, s->baseX);
    floatP x1 = fma((floatP)(hiX), s->scaleX, s->baseX);
    floatP y0 = fma((floatP)(loY), s->scaleY, s->baseY);
    floatP y1 = fma((floatP)(hiY), s->scaleY, s->baseY);
    floatP z0 = fma((floatP)(loZ), s->scaleZ, s->baseZ);
    floatP z1 = fma((floatP)(hiZ), s->scaleZ, s->baseZ);
    floatP enter = Lanes_Max(Lanes_Max(Lanes_Min(x0, x1), Lanes_Min(y0, y1)),
                             Lanes_Max(Lanes_Min(z0, z1), (floatP)(0.0f)));
    floatP leave = Lanes_Min(Lanes_Min(Lanes_Max(x0, x1), Lanes_Max(y0, y1)),
                             Lanes_Min(Lanes_Max(z0, z1), hitT));
    return select((floatP)(INFINITY), enter, (enter <= leave) & (enter < hitT));
}

#ifdef RT_WATERTIGHT
RT_DEFINE_WATERTIGHT_DELTA_T(Packet_WatertightDeltaT, floatP)

// The shear of Triangle_Intersect's watertight test, per ray (its first lines), and the
// origin's components on its axes. Coherent rays mostly share their axes: then kx, ky, kz
// hold them and a triangle's vertices are permuted once for all rays, not lane by lane.
inline void Packet_Shear(RayPacket* r) {
    floatP ax = fabs(r->dx), ay = fabs(r->dy), az = fabs(r->dz);
    intP kz = select(select((intP)(2), (intP)(1), ay >= az), select((intP)(2), (intP)(0), ax >= az),
                     ax >= ay);
    intP kx = select(kz + 1, (intP)(0), kz == 2);
    intP ky = select(kx + 1, (intP)(0), kx == 2);
    floatP dz = Packet_Component(r->dx, r->dy, r->dz, kz == 1, kz == 2);
    intP flip = dz < 0.0f;  // keeps the winding: swap kx and ky
    intP tmp = kx;
    kx = select(kx, ky, flip);
    ky = select(ky, tmp, flip);
    r->kx1 = kx == 1;
    r->kx2 = kx == 2;
    r->ky1 = ky == 1;
    r->ky2 = ky == 2;
    r->kz1 = kz == 1;
    r->kz2 = kz == 2;
    r->sx = Packet_Component(r->dx, r->dy, r->dz, r->kx1, r->kx2) / dz;
    r->sy = Packet_Component(r->dx, r->dy, r->dz, r->ky1, r->ky2) / dz;
    r->sz = 1.0f / dz;
    r->okx = Packet_Component(r->ox, r->oy, r->oz, r->kx1, r->kx2);
    r->oky = Packet_Component(r->ox, r->oy, r->oz, r->ky1, r->ky2);
    r->okz = Packet_Component(r->ox, r->oy, r->oz, r->kz1, r->kz2);
    bool same = !Packet_Any((kx != kx.s0) | (ky != ky.s0) | (kz != kz.s0));
    r->kx = same ? kx.s0 : -1;
    r->ky = ky.s0;
    r->kz = kz.s0;
}

// A vertex's components on each ray's axes kx, ky, kz.
inline void Packet_Permute(float3 v, const RayPacket* r, floatP* x, floatP* y, floatP* z) {
    if (r->kx >= 0) {
        *x = (floatP)(component(v, r->kx));
        *y = (floatP)(component(v, r->ky));
        *z = (floatP)(component(v, r->kz));
        return;
    }
    floatP vx = (floatP)(v.x), vy = (floatP)(v.y), vz = (floatP)(v.z);
    *x = Packet_Component(vx, vy, vz, r->kx1, r->kx2);
    *y = Packet_Component(vx, vy, vz, r->ky1, r->ky2);
    *z = Packet_Component(vx, vy, vz, r->kz1, r->kz2);
}

// Triangle_Intersect's watertight test (Woop, Benthin and Wald 2013) for every ray against
// one triangle, in its order of operations (component(v - o, k) is v[k] - o[k]); the lanes
// where it hits with 0 < t < hitT.
inline intP Packet_Triangle(global const Triangle* tri, const RayPacket* r, floatP hitT,
                            floatP* tOut, floatP* uOut, floatP* vOut) {
    floatP px, py, pz;
    Packet_Permute(f3(tri->v0), r, &px, &py, &pz);
    floatP Ak = pz - r->okz;
    floatP ax = (px - r->okx) - r->sx * Ak, ay = (py - r->oky) - r->sy * Ak;
    Packet_Permute(f3(tri->v1), r, &px, &py, &pz);
    floatP Bk = pz - r->okz;
    floatP bx = (px - r->okx) - r->sx * Bk, by = (py - r->oky) - r->sy * Bk;
    Packet_Permute(f3(tri->v2), r, &px, &py, &pz);
    floatP Ck = pz - r->okz;
    floatP cx = (px - r->okx) - r->sx * Ck, cy = (py - r->oky) - r->sy * Ck;
    floatP U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
    intP miss = ((U < 0.0f) | (V < 0.0f) | (W < 0.0f)) & ((U > 0.0f) | (V > 0.0f) | (W > 0.0f));
    floatP det = U + V + W;
    floatP T = U * r->sz * Ak + V * r->sz * Bk + W * r->sz * Ck;
    miss |= (det == 0.0f) | ((det < 0.0f) & (T >= 0.0f)) | ((det > 0.0f) & (T <= 0.0f));
    floatP rcp = 1.0f / det;
    floatP t = T * rcp;
    miss |= !(t < hitT);
    if (!Packet_Any(~miss)) return miss & 0;  // no lane hits: the bound is not needed
    miss |= t <= Packet_WatertightDeltaT(ax, ay, r->sz * Ak, bx, by, r->sz * Bk, cx, cy, r->sz * Ck,
                                         U, V, W, rcp);
    *tOut = t;
    *uOut = V * rcp;
    *vOut = W * rcp;
    return ~miss & (t > 0.0f) & (t < hitT);
}
#else
RT_DEFINE_MT_DELTA_T(Packet_MollerTrumboreDeltaT, floatP)

// Triangle_Intersect's Moller-Trumbore for every ray against one triangle, written out per
// component in the order of cross() and dot(); the lanes where it hits with 0 < t < hitT.
inline intP Packet_Triangle(global const Triangle* tri, const RayPacket* r, floatP hitT,
                            floatP* tOut, floatP* uOut, floatP* vOut) {
    float3 v0 = f3(tri->v0);
    float3 e1 = f3(tri->v1) - v0, e2 = f3(tri->v2) - v0;
    floatP hx = r->dy * e2.z - r->dz * e2.y;
    floatP hy = r->dz * e2.x - r->dx * e2.z;
    floatP hz = r->dx * e2.y - r->dy * e2.x;
    floatP a = e1.x * hx + e1.y * hy + e1.z * hz;
    floatP f = 1.0f / a;
    floatP sx = r->ox - v0.x, sy = r->oy - v0.y, sz = r->oz - v0.z;
    floatP u = f * (sx * hx + sy * hy + sz * hz);
    floatP qx = sy * e1.z - sz * e1.y;
    floatP qy = sz * e1.x - sx * e1.z;
    floatP qz = sx * e1.y - sy * e1.x;
    floatP v = f * (r->dx * qx + r->dy * qy + r->dz * qz);
    floatP t = f * (e2.x * qx + e2.y * qy + e2.z * qz);
    // Triangle_Intersect's early outs and conservative t > 0, then Hit_Triangle's 0 < t < hit->t.
    intP miss = (a == 0.0f) | (u < 0.0f) | (u > 1.0f) | (v < 0.0f) | (u + v > 1.0f) |
                (t <= Packet_MollerTrumboreDeltaT(sx, sy, sz, e1, e2, f));
    *tOut = t;
    *uOut = u;
    *vOut = v;
    return ~miss & (t > 0.0f) & (t < hitT);
}

#endif

// Tests the triangles of one leaf for every ray. Closest hit: a ray's hit becomes each nearer
// triangle (Hit_Triangle). Any hit: a ray that is occluded gets t = 0, which no box or triangle
// passes.
inline void Packet_Leaf(const SceneData* sc, int first, int count, const RayPacket* r, PacketHit* h,
                        bool anyHit) {
    for (int i = first; i < first + count; ++i) {
        floatP t, u, v;
        intP hit = Packet_Triangle(sc->triangles + i, r, h->t, &t, &u, &v);
        if (!Packet_Any(hit)) continue;
        h->kind = select(h->kind, (intP)(RT_KIND_TRIANGLE), hit);
        if (anyHit) {
            h->t = select(h->t, (floatP)(0.0f), hit);
            if (!Packet_Any(h->t > 0.0f)) return;
            continue;
        }
        h->t = select(h->t, t, hit);
        h->object = select(h->object, (intP)(i), hit);
        h->u = select(h->u, u, hit);
        h->v = select(h->v, v, hit);
    }
}

#ifdef RT_HAS_SPHERES
// Spheres of one leaf, ray by ray with Hit_Sphere (the scalar test, so the same t): scenes of
// many triangles hold a few spheres at most, and this keeps the arithmetic the single ray's.
inline void Packet_SphereLeaf(const SceneData* sc, int first, int count, const RayPacket* r,
                              PacketHit* h, bool anyHit) {
    float o[3][RT_PACKET], d[3][RT_PACKET], t[RT_PACKET];
    int kind[RT_PACKET], object[RT_PACKET];
    vstoreP(r->ox, 0, o[0]);
    vstoreP(r->oy, 0, o[1]);
    vstoreP(r->oz, 0, o[2]);
    vstoreP(r->dx, 0, d[0]);
    vstoreP(r->dy, 0, d[1]);
    vstoreP(r->dz, 0, d[2]);
    vstoreP(h->t, 0, t);
    vstoreP(h->kind, 0, kind);
    vstoreP(h->object, 0, object);
    for (int j = 0; j < RT_PACKET; ++j) {
        if (!(t[j] > 0.0f)) continue;  // an unused lane, or an occluded one
        Ray ray = makeRay((float3)(o[0][j], o[1][j], o[2][j]), (float3)(d[0][j], d[1][j], d[2][j]));
        Hit hit;
        hit.t = t[j];
        hit.kind = kind[j];
        hit.object = object[j];
        for (int i = first; i < first + count; ++i)
            if (Hit_Sphere(sc, i, ray, &hit) && anyHit) {
                hit.t = 0.0f;
                break;
            }
        t[j] = hit.t;
        kind[j] = hit.kind;
        object[j] = hit.object;
    }
    h->t = vloadP(0, t);
    h->kind = vloadP(0, kind);
    h->object = vloadP(0, object);
}
#endif

// Every ray's closest hit below h->t (its tMax, or a plane's hit), or with anyHit whether it
// is occluded (PacketHit).
inline void Wide_QueryPacket(const SceneData* sc, const RayPacket* r, PacketHit* h, bool anyHit) {
    global const WideNode* nodes = (global const WideNode*)sc->bvh;
    int stack[RT_WIDE_STACK];
    floatP stackT[RT_WIDE_STACK];  // every ray's entry distance of each deferred node
    int top = 0, index = 0;
    for (;;) {
        global const WideNode* n = nodes + index;
        PacketSlabs slabs = Packet_Slabs(n, r);
        // An empty slot (child -1; its box is the point at the origin) is neither tested nor
        // visited.
        floatP t[4];
        for (int k = 0; k < 4; ++k)
            t[k] = n->child[k] == -1
                       ? (floatP)(INFINITY)
                       : Packet_Enter(&slabs, slabs.lo[0][k], slabs.lo[1][k], slabs.lo[2][k],
                                      slabs.hi[0][k], slabs.hi[1][k], slabs.hi[2][k], h->t);
        // Leaves first: hits there shorten the rays before the inner children are ordered.
        for (int k = 0; k < 4; ++k) {
            if (n->count[k] == 0 || !Packet_Any(t[k] < h->t)) continue;
#ifdef RT_HAS_SPHERES
            if ((n->sphereMask >> k) & 1u)
                Packet_SphereLeaf(sc, n->child[k], n->count[k], r, h, anyHit);
            else
#endif
                Packet_Leaf(sc, n->child[k], n->count[k], r, h, anyHit);
            if (anyHit && !Packet_Any(h->t > 0.0f)) return;
        }
        // Inner children some ray enters before its hit, by the packet's nearest entry.
        int near[4];
        float nearT[4];
        floatP nearAll[4];
        int m = 0;
        for (int k = 0; k < 4; ++k) {
            if (n->count[k] != 0 || n->child[k] == -1) continue;
            floatP tk = select((floatP)(INFINITY), t[k], t[k] < h->t);
            float key = Packet_Smallest(tk);
            if (key == INFINITY) continue;
            int j = m++;
            while (j > 0 && nearT[j - 1] > key) {
                near[j] = near[j - 1];
                nearT[j] = nearT[j - 1];
                nearAll[j] = nearAll[j - 1];
                --j;
            }
            near[j] = n->child[k];
            nearT[j] = key;
            nearAll[j] = tk;
        }
        if (m > 0) {
            for (int j = m - 1; j > 0; --j) {
                stack[top] = near[j];
                stackT[top] = nearAll[j];
                ++top;
            }
            index = near[0];
            continue;
        }
        // Next: the most recently deferred node that some ray enters before its current hit.
        while (top > 0 && !Packet_Any(stackT[top - 1] < h->t)) --top;
        if (top == 0) return;
        index = stack[--top];
    }
}

// A packet from each ray's origin and direction, component by component: o and d hold
// RT_PACKET x values, then y, then z.
inline RayPacket Packet_Make(const float* o, const float* d) {
    RayPacket r;
    r.ox = vloadP(0, o);
    r.oy = vloadP(1, o);
    r.oz = vloadP(2, o);
    r.dx = vloadP(0, d);
    r.dy = vloadP(1, d);
    r.dz = vloadP(2, d);
    r.ix = Packet_InvDir(r.dx);
    r.iy = Packet_InvDir(r.dy);
    r.iz = Packet_InvDir(r.dz);
#ifdef RT_WATERTIGHT
    Packet_Shear(&r);
#endif
    return r;
}

// Loads rays first .. first + RT_PACKET - 1 of a batch (8 floats each: origin, tMax, direction,
// unused); lanes past count get tMax = -INFINITY and take no part.
inline RayPacket Packet_Load(global const float8* rays, int first, int count, floatP* tMax) {
    float o[3 * RT_PACKET], d[3 * RT_PACKET], tm[RT_PACKET];
    for (int j = 0; j < RT_PACKET; ++j) {
        bool used = first + j < count;
        float8 ray =
            used ? rays[first + j] : (float8)(0.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f);
        o[j] = ray.s0;
        o[RT_PACKET + j] = ray.s1;
        o[2 * RT_PACKET + j] = ray.s2;
        tm[j] = used ? ray.s3 : -INFINITY;
        d[j] = ray.s4;
        d[RT_PACKET + j] = ray.s5;
        d[2 * RT_PACKET + j] = ray.s6;
    }
    *tMax = vloadP(0, tm);
    return Packet_Make(o, d);
}

#endif
