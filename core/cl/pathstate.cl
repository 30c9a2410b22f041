// rtlab — the forward-weight path state (core/SHADING.md section 8): a ray that carries the weight
// its ancestors give it, so that a node's local term adds straight into the pixel and no tree is
// kept. The megakernel's weighted layout (a private depth-first stack) and the queue wavefront
// (wavefront/queue, a pool of such records in global memory) both step paths with these functions
// only, so both compute bit-identical weights and contributions.
#ifndef RTLAB_CL_PATHSTATE
#define RTLAB_CL_PATHSTATE
#include "ray_state.h"
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

// A record of the stored fields (RT_RAY_STATE_MEMBERS) from Pending `p`, and back, field by field
// from ray_state.h's list: RAY_STATE_CODEC(Record) defines void RayState_Pack_Record(const
// Pending*, Record*), which sets the record's state fields (not its others), and Pending
// RayState_Unpack_Record(Record).
#define RAY_STATE_PACK_F3(X, field, Field, member) q->field = F3(p->member);
#define RAY_STATE_PACK_META(X, field, Field) q->field = p->depth << 8 | p->type;
#define RAY_STATE_UNPACK_F3(X, field, Field, member) p.member = f3(q.field);
#define RAY_STATE_UNPACK_META(X, field, Field) \
    p.depth = q.field >> 8;                    \
    p.type = q.field & 0xff;
#define RAY_STATE_CODEC(Record)                                       \
    inline void RayState_Pack_##Record(const Pending* p, Record* q) { \
        RT_RAY_STATE(RAY_STATE_PACK_F3, RAY_STATE_PACK_META, _)       \
    }                                                                 \
    inline Pending RayState_Unpack_##Record(Record q) {               \
        Pending p;                                                    \
        RT_RAY_STATE(RAY_STATE_UNPACK_F3, RAY_STATE_UNPACK_META, _)   \
        return p;                                                     \
    }

// The same fields as a structure of arrays in global memory (the queue wavefront's pool): a
// struct of pointers, the kernel parameters that pass them (RAY_STATE_PARAMS(prefix): prefix ##
// Field, each with a trailing comma), and a ray's load, store and copy at index i.
#define RAY_STATE_SOA_F3(X, field, Field, member) global float* field;
#define RAY_STATE_SOA_META(X, field, Field) global int* field;
typedef struct RayStateArrays {
    RT_RAY_STATE(RAY_STATE_SOA_F3, RAY_STATE_SOA_META, _)
} RayStateArrays;
#define RAY_STATE_PARAM_F3(prefix, field, Field, member) global float *prefix##Field,
#define RAY_STATE_PARAM_META(prefix, field, Field) global int *prefix##Field,
#define RAY_STATE_PARAMS(prefix) RT_RAY_STATE(RAY_STATE_PARAM_F3, RAY_STATE_PARAM_META, prefix)
#define RAY_STATE_LOAD_F3(X, field, Field, member) p.member = vload3(i, r->field);
#define RAY_STATE_LOAD_META(X, field, Field) \
    {                                        \
        const int word = r->field[i];        \
        p.depth = word >> 8;                 \
        p.type = word & 0xff;                \
    }
#define RAY_STATE_STORE_F3(X, field, Field, member) vstore3(p->member, i, r->field);
#define RAY_STATE_STORE_META(X, field, Field) r->field[i] = p->depth << 8 | p->type;
#define RAY_STATE_COPY_F3(X, field, Field, member) vstore3(vload3(s, from->field), o, to->field);
#define RAY_STATE_COPY_META(X, field, Field) to->field[o] = from->field[s];

inline Pending RayState_Load(const RayStateArrays* r, int i) {
    Pending p;
    RT_RAY_STATE(RAY_STATE_LOAD_F3, RAY_STATE_LOAD_META, _)
    return p;
}

inline void RayState_Store(const RayStateArrays* r, int i, const Pending* p) {
    RT_RAY_STATE(RAY_STATE_STORE_F3, RAY_STATE_STORE_META, _)
}

// Ray s of `from` to slot o of `to`, as stored.
inline void RayState_Copy(const RayStateArrays* from, int s, const RayStateArrays* to, int o) {
    RT_RAY_STATE(RAY_STATE_COPY_F3, RAY_STATE_COPY_META, _)
}

#endif
