// rtlab — the persistent megakernel (Aila and Laine 2009's persistent threads): as many
// work-items as the device keeps busy at once, each taking its next pixel from a global counter
// once its own pixel is done, so that a lane whose ray tree ends early starts another pixel
// instead of idling until the warp's deepest tree is done. The per-pixel work is the weighted
// megakernel's (megakernel_sample.cl), so the image is the same to the bit.
#include "megakernel_sample.cl"

// Pixels [first, first + count) of the frame, in row-major order; *next counts the ones taken
// (zeroed by the host before each launch).
kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    for (;;) {
        const int k = atomic_inc(next);
        if (k >= count) return;
        const int pixel = first + k, y = pixel / settings.width, x = pixel - y * settings.width;
        float3 acc = Megakernel_Sample(&sc, x, y, 0);
        for (int s = 1; s < samples; ++s) acc += Megakernel_Sample(&sc, x, y, s);
        Megakernel_Store(image, pixel * 3, acc / (float)samples);
    }
}
