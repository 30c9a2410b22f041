// rtlab — the bounce loop's records as the OpenCL compiler sees them, for the tests
// (tests/persistent_test.cpp, BounceStateHasTheHostsLayout).
#include "bounce_state.h"
#include "types.h"

kernel void Bounce_Sizes(global uint* out) {
    out[0] = sizeof(BounceRay);
    out[1] = sizeof(BounceTerm);
    out[2] = sizeof(BounceHit);
    out[3] = __builtin_offsetof(BounceHit, ray);
}
