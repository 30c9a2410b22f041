// rtlab — the per-pixel ray tree (report 3.2, core/SHADING.md sections 6 and 8). Both pipelines
// build and combine trees with these functions and nothing else, which is what makes their
// images bit-identical (the tree wavefront's image kernel visits only traced slots, but shades
// each with RayTree_NodeColor on the same inputs RayTree_Combine gives it). Node i at depth k has
// children i*C + 1 + slot (slot 0 reflection, slot 1 refraction); C = RT_BRANCH. A tree of B levels
// below the root has N nodes (RayTree_NodeCount); programs that keep a whole tree in private memory
// know N at build time as RT_TREE_NODES.
#ifndef RTLAB_CL_RAYTREE
#define RTLAB_CL_RAYTREE
#include "camera.cl"
#include "shade.cl"

inline int RayTree_Depth(int i) {
#if RT_BRANCH == 1
    return i;
#else
    return 31 - (int)clz((uint)(i + 1));
#endif
}

// N: the slots of a tree whose deepest node has depth `bounces` (treeNodeCount on the host).
inline int RayTree_NodeCount(int bounces) {
#if RT_BRANCH == 1
    return bounces + 1;
#else
    return (2 << bounces) - 1;
#endif
}

// Ray type of heap slot i > 0: slot 0 of a parent is its reflection, slot 1 its refraction.
inline int RayTree_SlotType(int i) {
    return (i - 1) % RT_BRANCH == 0 ? RT_RAY_REFLECTION : RT_RAY_REFRACTION;
}

// Robust sphere hits (Haines et al., Ray Tracing Gems ch. 7, SHADING.md section 2): the outward
// normal from the quantities of the stable test, not from (p - c) / r. f = oc + b d is the
// centre-to-ray offset and the root is t = b -/+ h, so p - c = f -/+ h d; f's rounding along d
// (from b) is projected out first. A float hit point one ulp off a tiny sphere far away no
// longer skews the normal; the point is then put back on the sphere.
inline float3 RayTree_SphereNormal(Ray ray, float3 center, float radius, float t) {
    float3 oc = ray.origin - center;
    float b = -dot(oc, ray.dir);
    float3 f = oc + b * ray.dir;
    f -= dot(f, ray.dir) * ray.dir;
    float h = sqrt(fmax(radius * radius - dot(f, f), 0.0f));
    return normalize(t < b ? f - h * ray.dir : f + h * ray.dir);
}

// Geometric normal of a traced hit, facing the incoming ray like node->normal.
inline float3 RayTree_GeometricNormal(const SceneData* sc, const Node* node) {
#ifdef RT_HAS_TRIANGLES
    if (node->kind == RT_KIND_TRIANGLE) {
        Triangle tri = sc->triangles[node->object];
        float3 v0 = f3(tri.v0);
        float3 g = normalize(cross(f3(tri.v1) - v0, f3(tri.v2) - v0));
        return (node->flags & RT_NODE_INSIDE) ? -g : g;
    }
#endif
    return f3(node->normal);
}

// Where a secondary ray leaves a traced hit: on the side the normal faces (side +1: reflection
// and shadow rays) or the other (-1: refraction). Section 3: fixed or scaled distance along the
// shading normal, or (RT_BOUND_OFFSET) just past the hit point's rounding-error bound.
inline float3 RayTree_SpawnOrigin(const SceneData* sc, const Node* node, float side) {
    float3 p = f3(node->point);
#ifdef RT_BOUND_OFFSET
    float3 err = (float3)(Shade_Offset(p) / 3.0f);  // a kind without a case below
#ifdef RT_HAS_SPHERES
    if (node->kind == RT_KIND_SPHERE) {
        Sphere s = sc->spheres[node->object];
        err = Shade_SphereError(f3(s.center), s.radius, normalize(f3(node->normal)));
    }
#endif
#ifdef RT_HAS_PLANES
    if (node->kind == RT_KIND_PLANE) err = Shade_PlaneError(p, sc->planes[node->object].offset);
#endif
#ifdef RT_HAS_TRIANGLES
    if (node->kind == RT_KIND_TRIANGLE) {
        Triangle tri = sc->triangles[node->object];
        err = Shade_TriangleError(f3(tri.v0), f3(tri.v1), f3(tri.v2));
    }
#endif
    return Shade_SpawnOrigin(p, RayTree_GeometricNormal(sc, node), err, side);
#else
    return p + (side * Shade_Offset(p)) * f3(node->normal);
#endif
}

// A ray's trace in three stages, which every scheduler calls: the closest hit (Scene_Intersect),
// the surface it found (RayTree_Surface: point, facing normal, material), and the shadow rays
// from that surface (RayTree_CastShadows). Shading is the fourth (RayTree_NodeColor, or a shade
// kernel of the queue wavefront). The megakernel and the tree wavefront run the first three in
// one call (RayTree_TraceNode); the queue wavefront runs each in a kernel of its own.

// The node of `ray` from its closest hit (Scene_Intersect's, or a packet's lane of the same hit:
// wavefront/queue/queue_packet.cl): point, facing normal and material, no light occluded yet.
RT_SURFACE_LINKAGE Node RayTree_Surface(const SceneData* sc, Ray ray, Hit hit) {
    Node n;
    n.dir = F3(ray.dir);
    n.object = hit.object;
    n.kind = (uchar)hit.kind;
    n.flags = (uchar)RT_NODE_TRACED;
    n.material = 0;
    for (int j = 0; j < RT_NODE_LIGHTS; ++j) n.occluded[j] = 0;
    n.point = F3((float3)(0.0f, 0.0f, 0.0f));
    n.normal = n.point;
    if (hit.kind == RT_KIND_MISS) return n;

    float3 p = ray.origin + hit.t * ray.dir;
    float3 normal = (float3)(0.0f, 0.0f, 1.0f);
    bool inside = false;
    int material = 0;
#ifdef RT_HAS_SPHERES
    if (hit.kind == RT_KIND_SPHERE) {
        Sphere s = sc->spheres[hit.object];
#ifdef RT_ROBUST_SPHERE
        normal = RayTree_SphereNormal(ray, f3(s.center), s.radius, hit.t);
        p = f3(s.center) + s.radius * normal;
#else
        normal = (p - f3(s.center)) / s.radius;  // the report's normal
#ifdef RT_BOUND_OFFSET
        // The report's t is off by up to an ulp of |o - c| (cancellation in -b - s): put the
        // point back on the sphere so that the sphere's error bound holds for it.
        p = f3(s.center) + s.radius * normalize(normal);
#endif
#endif
        inside = dot(normal, ray.dir) > 0.0f;
        material = s.material;
    }
#endif
#ifdef RT_HAS_PLANES
    if (hit.kind == RT_KIND_PLANE) {
        Plane pl = sc->planes[hit.object];
        normal = f3(pl.normal);
#ifdef RT_BOUND_OFFSET
        p += (pl.offset - dot(normal, p)) * normal;  // onto the plane: an error bound from p alone
#endif
        inside = dot(normal, ray.dir) > 0.0f;
        material = pl.material;
    }
#endif
#ifdef RT_HAS_TRIANGLES
    if (hit.kind == RT_KIND_TRIANGLE) {
        Triangle tri = sc->triangles[hit.object];
        float3 v0 = f3(tri.v0);
        float3 geometric = cross(f3(tri.v1) - v0, f3(tri.v2) - v0);
        float u = hit.uv.x, v = hit.uv.y;
        normal = normalize((1.0f - u - v) * f3(tri.n0) + u * f3(tri.n1) + v * f3(tri.n2));
#ifdef RT_BOUND_OFFSET
        p = (1.0f - u - v) * v0 + u * f3(tri.v1) + v * f3(tri.v2);  // error bounded by vertices
#endif
        inside = dot(geometric, ray.dir) > 0.0f;
        material = tri.material;
    }
#endif
    if (inside) {
        normal = -normal;
        n.flags |= (uchar)RT_NODE_INSIDE;
    }
    n.point = F3(p);
    n.normal = F3(normal);
    n.material = (ushort)material;
    return n;
}

// The shadow rays of a surface node (not a miss): how many of each light's samples are
// occluded. key: Sampling_PointKey of the ray's pixel, AA sample and depth, which places the
// samples on the lights (core/sampling.h). The point and normal are the node's own, so a stage
// that reads the node back from memory casts exactly the rays RayTree_TraceNode casts.
RT_SHADOWS_LINKAGE void RayTree_CastShadows(const SceneData* sc, Node* node, uint key) {
    float3 p = f3(node->point), normal = f3(node->normal);
    float3 origin = RayTree_SpawnOrigin(sc, node, 1.0f);
    for (int j = 0; j < sc->settings.lightCount; ++j)
        node->occluded[j] = (uchar)Shade_OcclusionFrom(sc, p, normal, origin, j, key);
}

// Traces one ray of the given RT_RAY_* type through the three stages: closest hit, surface,
// shadow rays (key as RayTree_CastShadows).
inline Node RayTree_TraceNode(const SceneData* sc, Ray ray, int type, uint key) {
    RT_COUNT_RAY(sc, type);
    (void)type;
    Hit hit = Scene_Intersect(sc, ray, INFINITY);
    Node n = RayTree_Surface(sc, ray, hit);
    if (hit.kind != RT_KIND_MISS) RayTree_CastShadows(sc, &n, key);
    return n;
}

// The first two stages only, for a scheduler that casts the shadow rays in a stage of its own.
inline Node RayTree_TraceSurface(const SceneData* sc, Ray ray, int type) {
    RT_COUNT_RAY(sc, type);
    (void)type;
    return RayTree_Surface(sc, ray, Scene_Intersect(sc, ray, INFINITY));
}

// The child ray of `parent` (at `depth`) in `slot`, or false when the parent has no such child.
inline bool RayTree_ChildRay(const SceneData* sc, const Node* parent, int depth, int slot,
                             Ray* out) {
    if (!(parent->flags & RT_NODE_TRACED) || parent->kind == RT_KIND_MISS) return false;
    if (depth >= sc->settings.bounces) return false;
    Material m = sc->materials[parent->material];
    float3 n = f3(parent->normal), d = f3(parent->dir);
    if (slot == 0) {
        if (!(m.reflectance > 0.0f || m.opacity < 1.0f)) return false;
        *out = makeRay(RayTree_SpawnOrigin(sc, parent, 1.0f), normalize(Shade_Reflect(d, n)));
        return true;
    }
    if (!(m.opacity < 1.0f)) return false;
    float eta = (parent->flags & RT_NODE_INSIDE) ? m.ior : 1.0f / m.ior;
    float3 t;
    if (!Shade_Refract(d, n, eta, &t)) return false;
    *out = makeRay(RayTree_SpawnOrigin(sc, parent, -1.0f), normalize(t));
    return true;
}

// Fresnel/reflectance factor F and effective opacity o of a hit node (section 8).
inline void RayTree_Mix(const SceneData* sc, const Node* node, bool hasRefl, bool hasRefr, float* F,
                        float* o) {
    Material m = sc->materials[node->material];
    *F = 0.0f;
    if (hasRefl) {
        if (m.opacity < 1.0f) {
            bool in = (node->flags & RT_NODE_INSIDE) != 0;
            *F = Shade_Fresnel(-dot(f3(node->dir), f3(node->normal)), in ? m.ior : 1.0f,
                               in ? 1.0f : m.ior);
        } else {
            *F = m.reflectance;
        }
    }
    *o = hasRefr ? m.opacity : 1.0f;
}

// Colour of a node from its children's colours.
inline float3 RayTree_NodeColor(const SceneData* sc, const Node* node, bool hasRefl, float3 refl,
                                bool hasRefr, float3 refr) {
    if (node->kind == RT_KIND_MISS) return Shade_Environment(sc, f3(node->dir));
    float F, o;
    RayTree_Mix(sc, node, hasRefl, hasRefr, &F, &o);
    float3 base = Shade_Base(sc, node);
    float3 transmission = o * base + (1.0f - o) * refr;
    return (1.0f - F) * transmission + F * refl;
}

#ifdef RT_TREE_NODES
// Combines a private copy of a pixel's tree from the deepest node up; colours[0] is the pixel.
inline float3 RayTree_Combine(const SceneData* sc, const Node* nodes, float3* colors) {
    for (int i = RT_TREE_NODES - 1; i >= 0; --i) {
        if (!(nodes[i].flags & RT_NODE_TRACED)) continue;
        int c0 = i * RT_BRANCH + 1;
        bool hasRefl = c0 < RT_TREE_NODES && (nodes[c0].flags & RT_NODE_TRACED);
        float3 refl = hasRefl ? colors[c0] : (float3)(0.0f, 0.0f, 0.0f);
        bool hasRefr = false;
        float3 refr = (float3)(0.0f, 0.0f, 0.0f);
#if RT_BRANCH == 2
        hasRefr = c0 + 1 < RT_TREE_NODES && (nodes[c0 + 1].flags & RT_NODE_TRACED);
        if (hasRefr) refr = colors[c0 + 1];
#endif
        colors[i] = RayTree_NodeColor(sc, &nodes[i], hasRefl, refl, hasRefr, refr);
    }
    return colors[0];
}
#endif  // RT_TREE_NODES

// Pixel (x, y)'s primary ray for the AA sample `sample` of the n x n grid.
inline Ray RayTree_PrimaryRay(const SceneData* sc, int x, int y, int sample) {
    return Camera_PrimaryRay(&sc->settings, x, y,
                             Camera_SampleOffset(sample, sc->settings.aaSamples));
}

// Adaptive anti-aliasing (section 11): a pixel is an edge when its centre sample differs from a
// 4-neighbour's by more than 0.1 in some channel.
inline bool RayTree_IsEdge(global const float* centers, int x, int y, int w, int h) {
    int i = (y * w + x) * 3;
    float3 c = (float3)(centers[i], centers[i + 1], centers[i + 2]);
    int nx[4] = {x - 1, x + 1, x, x};
    int ny[4] = {y, y, y - 1, y + 1};
    for (int k = 0; k < 4; ++k) {
        if (nx[k] < 0 || nx[k] >= w || ny[k] < 0 || ny[k] >= h) continue;
        int j = (ny[k] * w + nx[k]) * 3;
        float3 e = fabs((float3)(centers[j], centers[j + 1], centers[j + 2]) - c);
        if (fmax(e.x, fmax(e.y, e.z)) > 0.1f) return true;
    }
    return false;
}

#endif
