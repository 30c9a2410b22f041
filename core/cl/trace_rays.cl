// rtlab — batches of given rays through the scene queries of both pipelines (Scene_Intersect,
// Scene_Occluded, and so the --accel structure), for the Embree peer benchmark
// (bench/trace_bench.cpp, issue 18). A ray is 8 floats: origin, tMax, direction, unused.
// Built with a scene's featureDefines and bound with DeviceScene::setArgs.
#include "scene.cl"

// From: rays. To: t of the closest hit below tMax, -1 on a miss.
kernel void Rays_Closest(RT_SCENE_PARAMS, global const float8* rays, global float* t,
                           int count) {
    size_t i = get_global_id(0);
    if (i >= (size_t)count) return;  // the work-group padding
    RT_SCENE_INIT(sc);
    float8 r = rays[i];
    Hit h = Scene_Intersect(&sc, makeRay(r.s012, r.s456), r.s3);
    t[i] = h.kind == RT_KIND_MISS ? -1.0f : h.t;
}

// From: rays. To: 1 where something lies between the origin and tMax, else 0.
kernel void Rays_Occluded(RT_SCENE_PARAMS, global const float8* rays,
                            global int* occluded, int count) {
    size_t i = get_global_id(0);
    if (i >= (size_t)count) return;  // the work-group padding
    RT_SCENE_INIT(sc);
    float8 r = rays[i];
    occluded[i] = Scene_Occluded(&sc, makeRay(r.s012, r.s456), r.s3) ? 1 : 0;
}
