// rtlab — the bounce loop's records (wavefront/bounce/bounce.cl), shared by the host (inside
// namespace rt::dev, after core/types.h) and the device, under core/types.h's layout rules.
#ifndef RTLAB_BOUNCE_STATE_H
#define RTLAB_BOUNCE_STATE_H

// The host's includes in angle brackets, so that the kernel-source resolver, which expands every
// quoted #include, leaves them to the preprocessor, which skips them on the device; there the
// kernel files include types.h first.
#ifdef __OPENCL_C_VERSION__
#include "ray_state.h"
#include "types.h"
#else
#include <core/ray_state.h>
#include <core/types.h>
#endif

RT_DEV_BEGIN

// A work-group's rays of one bounce wait in global memory in these records: the weighted
// megakernel's pending ray (core/ray_state.h's fields) packed without float3 padding, the pixel
// (its index among the batch the work-group holds) and the ray's slot in that pixel's tree
// (children of slot i at i*C + 1 + k, as Node's).
// clang-format off
typedef struct BounceRay {
    RT_RAY_STATE_MEMBERS  // core/ray_state.h: origin, dir, weight, depthType (depth << 8 | type)
    int32_t pixel;
    int32_t slot;
} BounceRay;
// clang-format on

// The staged loop (bounce-staged) keeps a bounce's traced rays here between the trace and the
// passes after it: the hit, the ray, its key and its rank among the hits of that key.
typedef struct BounceHit {
    Node node;
    BounceRay ray;
    int32_t key, rank;
    int32_t pad[2];
} BounceHit;

// What a traced ray added to its pixel, and which children it spawned (bit 0 reflection, bit 1
// refraction): one per slot of every pixel's tree, so that the pixel's terms can be summed in the
// weighted megakernel's order once the tree is done.
typedef struct BounceTerm {
    Float3 term;
    int32_t children;
} BounceTerm;

RT_DEV_END

#ifndef __OPENCL_C_VERSION__
static_assert(sizeof(rt::dev::BounceRay) == 48 && sizeof(rt::dev::BounceTerm) == 16 &&
              sizeof(rt::dev::BounceHit) == 112);
namespace rt::dev {
// The device's size of a BounceHit in the programs of a scene of `lights` lights (its Node's
// occlusion counts, core/types.h nodeLights).
constexpr std::size_t bounceHitBytes(std::size_t lights) {
    return sizeof(BounceHit) - RT_NODE_LIGHTS + std::size_t(nodeLights(lights));
}
}  // namespace rt::dev
#endif

#endif  // RTLAB_BOUNCE_STATE_H
