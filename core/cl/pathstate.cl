// rtlab — the forward-weight path state (core/SHADING.md section 8): a ray that carries the weight
// its ancestors give it, so that a node's local term adds straight into the pixel and no tree is
// kept. The megakernel's weighted layout (a private depth-first stack) and the queue wavefront
// (wavefront/queue, a pool of such records in global memory) both step paths with these functions
// only, so both compute bit-identical weights and contributions.
#ifndef RTLAB_CL_PATHSTATE
#define RTLAB_CL_PATHSTATE
#include "raytree.cl"

// One pending ray: the ray, its weight, its depth in the tree and its RT_RAY_* type.
typedef struct Pending {
    Ray ray;
    float3 weight;
    int depth;
    int type;
} Pending;

inline Pending PathState_Make(Ray ray, float3 weight, int depth, int type) {
    Pending p;
    p.ray = ray;
    p.weight = weight;
    p.depth = depth;
    p.type = type;
    return p;
}

// The root of a path: pixel (x, y)'s primary ray for AA sample `sample`, weight 1.
inline Pending PathState_Primary(const SceneData* sc, int x, int y, int sample) {
    return PathState_Make(RayTree_PrimaryRay(sc, x, y, sample), (float3)(1.0f, 1.0f, 1.0f), 0,
                          RT_RAY_PRIMARY);
}

// What a ray that missed everything adds to its pixel: its weight times the environment.
inline float3 PathState_Miss(const SceneData* sc, const Pending* p) {
    return p->weight * Shade_Environment(sc, p->ray.dir);
}

// The forward-weight step of a ray that hit `node`: returns the node's local term
// w (1 - F) o base, and the children with weights w F (reflection) and w (1 - F)(1 - o)
// (refraction). mayReflect / mayRefract let a caller that knows the material class skip a
// child that cannot exist (RayTree_ChildRay would say no anyway), and `pattern` (Shade_BaseOf)
// one that knows its procedural pattern skip the others' code, so the result is the same.
RT_STEP_LINKAGE float3 PathState_Step(const SceneData* sc, const Node* node, const Pending* p,
                                      bool mayReflect, bool mayRefract, int pattern, Pending* refl,
                                      bool* hasRefl, Pending* refr, bool* hasRefr) {
    Ray r0, r1;
    *hasRefl = mayReflect && RayTree_ChildRay(sc, node, p->depth, 0, &r0);
    *hasRefr = RT_BRANCH == 2 && mayRefract && RayTree_ChildRay(sc, node, p->depth, 1, &r1);
    float F, o;
    RayTree_Mix(sc, node, *hasRefl, *hasRefr, &F, &o);
    if (*hasRefl) *refl = PathState_Make(r0, p->weight * F, p->depth + 1, RT_RAY_REFLECTION);
    if (*hasRefr)
        *refr = PathState_Make(r1, p->weight * ((1.0f - F) * (1.0f - o)), p->depth + 1,
                               RT_RAY_REFRACTION);
    return p->weight * ((1.0f - F) * o) * Shade_BaseOf(sc, node, pattern);
}

#endif
