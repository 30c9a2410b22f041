// rtlab — the persistent megakernel (Aila and Laine 2009's persistent threads): as many
// work-items as the device keeps busy at once, each taking its next pixel from a global counter
// as soon as its own pixel is done.
//
// The loop is flat: one iteration traces one ray of whatever pixel the lane holds, and a lane
// whose stack runs dry fetches its next pixel inside the same iteration. A loop over pixels with a
// loop over rays inside it would gain nothing on a SIMT machine: the lanes that leave the inner
// loop wait at its end for the warp's deepest ray tree, exactly as in the one-pixel megakernel.
// Flat, a warp keeps all of its lanes tracing until the counter runs out.
//
// The per-ray work is the weighted megakernel's (Megakernel_TraceNext), and each pixel's rays and
// samples are summed in the same order, so the image is the same to the bit.
#include "megakernel_sample.cl"

// Pixels [first, first + count) of the frame, in row-major order; *next counts the ones taken
// (zeroed by the host before each launch).
kernel void Persistent_Render(RT_SCENE_PARAMS, global float* image, global int* next, int first,
                              int count) {
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0, pixel = -1, x = 0, y = 0, sample = 0;
    float3 color = (float3)(0.0f, 0.0f, 0.0f);  // the current sample's sum
    float3 acc = color;                         // the pixel's sum over its finished samples
    for (;;) {
        if (top == 0) {
            if (pixel >= 0) {  // the current sample's tree is done
                acc = sample == 0 ? color : acc + color;
                if (++sample == samples) {
                    Megakernel_Store(image, pixel * 3, acc / (float)samples);
                    pixel = -1;
                }
            }
            if (pixel < 0) {
                const int k = atomic_inc(next);
                if (k >= count) return;
                pixel = first + k;
                y = pixel / settings.width;
                x = pixel - y * settings.width;
                sample = 0;
            }
            stack[top++] = RT_STACK_PUSH(PathState_Primary(&sc, x, y, sample));
            color = (float3)(0.0f, 0.0f, 0.0f);
        }
        RT_COUNT_WARP_STEP(&sc);  // every lane that holds a pixel traces a ray
        color += Megakernel_TraceNext(&sc, stack, &top, x, y, sample);
    }
}
