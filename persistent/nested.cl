// rtlab — the persistent megakernel's nested loop (--persistent-schedule nested): Aila and Laine's
// own shape, a loop over pixels around the one-pixel megakernel's loop over rays. The work-group
// takes a pixel for each of its lanes with one atomic add, each lane renders its pixel as
// Megakernel_Render does, and the group takes the next ones once all of its lanes are done: the
// megakernel's own work-groups, dealt by a counter to a launch that fills the device once. Taken a
// work-group at a time, a compute unit's warps work on one patch of the frame, whose rays share the
// caches, instead of on patches taken a warp at a time as the warps come free. Against the flat
// loop it has no per-ray vote or refill test, and its lanes wait for the group's deepest tree. Same
// pixels, same sums, same bits.
#include "handout.cl"

kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    const int lane = (int)get_local_id(0);
    local int base;  // the group's first pixel this round
    for (;;) {
        barrier(CLK_LOCAL_MEM_FENCE);  // every lane has read the last round's base
        if (lane == 0) base = atomic_add(next, (int)get_local_size(0));
        barrier(CLK_LOCAL_MEM_FENCE);
        if (base >= count) break;  // the whole group leaves together: every lane meets each barrier
        const int k = base + lane;
        if (k < count) {
            const int2 xy = Persistent_PixelOf(k, first, count, settings.width);
            Megakernel_Store(image, (xy.y * settings.width + xy.x) * 3,
                             Megakernel_PixelMean(&sc, xy.x, xy.y, samples));
        }
    }
}
