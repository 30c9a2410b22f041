// rtlab — the monolithic kernel (report 3.2.4): one launch per frame, one pixel per work-item
// (megakernel_sample.cl holds the pixel's work and its two layouts of the ray tree).
#include "megakernel_sample.cl"

// One launch per frame (or per tile of rows): every AA sample of every pixel, summed in sample
// order and divided once, exactly as the wavefront pipeline's passes do.
kernel void Megakernel_Render(RT_SCENE_PARAMS, global float* image) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= settings.height) return;
    RT_SCENE_INIT(sc);
    const int samples = settings.aaSamples * settings.aaSamples;
    Megakernel_Store(image, (y * settings.width + x) * 3, Megakernel_PixelMean(&sc, x, y, samples));
}

// Adaptive anti-aliasing, pass 1: the centre sample of every pixel.
kernel void Megakernel_RenderCenters(RT_SCENE_PARAMS, global float* centers) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= settings.height) return;
    RT_SCENE_INIT(sc);
    sc.settings.aaSamples = 1;  // a 1 x 1 grid: its only sample is the pixel centre
    Megakernel_Store(centers, (y * settings.width + x) * 3, Megakernel_Sample(&sc, x, y, 0));
}

// Adaptive anti-aliasing, pass 2: edges get the full n x n grid, the rest keep their centre.
kernel void Megakernel_RenderEdges(RT_SCENE_PARAMS, global const float* centers,
                                   global float* image) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= settings.height) return;
    RT_SCENE_INIT(sc);
    int i = (y * settings.width + x) * 3;
    if (!RayTree_IsEdge(centers, x, y, settings.width, settings.height)) {
        image[i] = centers[i];
        image[i + 1] = centers[i + 1];
        image[i + 2] = centers[i + 2];
        return;
    }
    Megakernel_Store(image, i,
                     Megakernel_PixelMean(&sc, x, y, settings.aaSamples * settings.aaSamples));
}
