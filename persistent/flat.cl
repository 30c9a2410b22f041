// rtlab — the persistent megakernel's flat loop (--persistent-schedule flat, the default):
// Aila and Laine 2009's persistent threads with one loop over rays. Each iteration traces one ray
// of whatever pixel the lane holds, and a lane whose stack runs dry takes its next pixel at the
// top of an iteration. A loop over pixels with a loop over rays inside it gains nothing on
// divergent work: the lanes that leave the inner loop wait at its end for the warp's deepest ray
// tree, exactly as in the one-pixel megakernel (that is nested.cl, the coherent scenes' best).
#include "handout.cl"

// Pixels [first, first + count) of the frame; *next counts the ones taken (zeroed by the host
// before each launch).
kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0;
    PersistentLane l;
    l.pixel = -1;
    for (;;) {
        Persistent_EndOfTree(&sc, image, &l, stack, &top, samples);
        uint wanting;
        const bool refillNow = Persistent_Refill(l.pixel < 0, &wanting);
        if (l.pixel < 0 && refillNow) {
            const int k = Persistent_TakeTogether(next, wanting);
            if (k >= count) return;
            Persistent_Begin(&sc, &l, stack, &top, k, first, count);
        }
        if (l.pixel < 0) continue;
        RT_COUNT_WARP_STEP(&sc);  // the lanes that trace a ray this step
        l.color += Megakernel_TraceNext(&sc, stack, &top, l.xy.x, l.xy.y, l.sample);
    }
}
