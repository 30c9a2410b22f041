// rtlab — the per-ray state every design stores between steps, defined once (as Cycles'
// state_template.h defines its integrator state): a pending ray's fields, each listed with how it
// is stored, and expanded wherever a design keeps rays outside registers: a record's members
// (RT_RAY_STATE_MEMBERS) and its pack and unpack (RAY_STATE_CODEC, core/cl/pathstate.cl), a
// structure of arrays in global memory with its kernel parameters, loads and stores
// (RayStateArrays, pathstate.cl), and on the host the buffers and kernel argument names of such
// arrays. Each pipeline's own storage (its stack record, pool or ray lists) is declared in its
// folder from these. In registers a ray is core/cl/pathstate.cl's Pending.
//
// RT_RAY_STATE(FLOAT3, META, X) calls, in storage order,
//   FLOAT3(X, field, Field, member)  three floats, Pending's float3 `member`;
//   META(X, field, Field)            one 32-bit word, Pending's depth << 8 | type;
// X is the caller's, passed through (a parameter prefix, a record).
// `field` names a struct member or a device pointer, `Field` the suffix of a kernel parameter
// (prefix ## Field: "raysOrigin"), which the host sets by the same name.
// Plain macros, valid C++ and OpenCL C alike.
#ifndef RTLAB_RAY_STATE_H
#define RTLAB_RAY_STATE_H

#define RT_RAY_STATE(FLOAT3, META, X)     \
    FLOAT3(X, origin, Origin, ray.origin) \
    FLOAT3(X, dir, Dir, ray.dir)          \
    FLOAT3(X, weight, Weight, weight)     \
    META(X, depthType, Meta)

// A record's members (core/types.h's layout rules: Float3, int32_t).
#define RT_RAY_STATE_MEMBER_F3(X, field, Field, member) Float3 field;
#define RT_RAY_STATE_MEMBER_META(X, field, Field) int32_t field;
#define RT_RAY_STATE_MEMBERS RT_RAY_STATE(RT_RAY_STATE_MEMBER_F3, RT_RAY_STATE_MEMBER_META, _)

// The bytes of each field stored (the queue's pool: float3 fields as three floats).
#define RT_RAY_STATE_F3_BYTES 12
#define RT_RAY_STATE_META_BYTES 4

#endif
