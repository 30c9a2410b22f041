// rtlab — batches of given rays through the scene queries of both pipelines (Scene_Intersect,
// Scene_Occluded, and so the --accel structure), for the Embree peer benchmark
// (bench/trace_bench.cpp). A ray is 8 floats: origin, tMax, direction, unused.
// Built with a scene's featureDefines and bound with DeviceScene::setArgs. With RT_ACCEL_WIDE
// and triangles alone, the packet kernels trace RT_PACKET rays per work-item (CPU devices).
#include "scene.cl"

// From: rays. To: t of the closest hit below tMax, -1 on a miss.
kernel void Rays_Closest(RT_SCENE_PARAMS, global const float8* rays, global float* t, int count) {
    size_t i = get_global_id(0);
    if (i >= (size_t)count) return;  // the work-group padding
    RT_SCENE_INIT(sc);
    float8 r = rays[i];
    Hit h = Scene_Intersect(&sc, makeRay(r.s012, r.s456), r.s3);
    t[i] = h.kind == RT_KIND_MISS ? -1.0f : h.t;
}

// From: rays. To: 1 where something lies between the origin and tMax, else 0.
kernel void Rays_Occluded(RT_SCENE_PARAMS, global const float8* rays, global int* occluded,
                          int count) {
    size_t i = get_global_id(0);
    if (i >= (size_t)count) return;  // the work-group padding
    RT_SCENE_INIT(sc);
    float8 r = rays[i];
    occluded[i] = Scene_Occluded(&sc, makeRay(r.s012, r.s456), r.s3) ? 1 : 0;
}

#if defined(RT_ACCEL_WIDE) && defined(RT_HAS_TRIANGLES) && !defined(RT_HAS_SPHERES) && \
    !defined(RT_HAS_PLANES)
#include "accel_wide_packet.cl"

// From: rays, RT_PACKET per work-item. To: as Rays_Closest, ray by ray.
kernel void Rays_ClosestPacket(RT_SCENE_PARAMS, global const float8* rays, global float* t,
                               int count) {
    int first = (int)get_global_id(0) * RT_PACKET;
    if (first >= count) return;  // the work-group padding
    RT_SCENE_INIT(sc);
    floatP tMax;
    RayPacket r = Packet_Load(rays, first, count, &tMax);
    PacketHit h = PacketHit_Make(tMax);
    Wide_QueryPacket(&sc, &r, &h, false);
    float out[RT_PACKET];
    vstoreP(select((floatP)(-1.0f), h.t, h.kind != RT_KIND_MISS), 0, out);
    for (int j = 0; j < RT_PACKET && first + j < count; ++j) t[first + j] = out[j];
}

// From: rays, RT_PACKET per work-item. To: as Rays_Occluded, ray by ray.
kernel void Rays_OccludedPacket(RT_SCENE_PARAMS, global const float8* rays, global int* occluded,
                                int count) {
    int first = (int)get_global_id(0) * RT_PACKET;
    if (first >= count) return;  // the work-group padding
    RT_SCENE_INIT(sc);
    floatP tMax;
    RayPacket r = Packet_Load(rays, first, count, &tMax);
    PacketHit h = PacketHit_Make(tMax);
    Wide_QueryPacket(&sc, &r, &h, true);
    int out[RT_PACKET];
    vstoreP((h.kind != RT_KIND_MISS) & 1, 0, out);
    for (int j = 0; j < RT_PACKET && first + j < count; ++j) occluded[first + j] = out[j];
}
#endif
