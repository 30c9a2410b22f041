// rtlab — the per-ray state every design stores between steps, defined once (as Cycles'
// state_template.h defines its integrator state): a pending ray's fields, each listed with how it
// is stored, and expanded wherever a design keeps rays outside registers:
//   * the megakernel's packed stack record (PackedPending, megakernel/megakernel_sample.cl);
//   * the queue wavefront's pool, a structure of arrays: its kernels' parameters and loads and
//     stores (wavefront/queue/queue.cl) and the host's buffers and argument names
//     (wavefront/queue/queue.h, queue.cpp);
//   * the bounce loop's ray lists (BounceRay, wavefront/bounce/bounce_state.h).
// In registers a ray is core/cl/pathstate.cl's Pending; RAY_STATE_PACK / RAY_STATE_UNPACK
// (pathstate.cl) turn one into the other, field by field from this list.
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
