// Packet traversal of the wide BVH (core/cl/accel_wide_packet.cl): packets of 8 and
// 16 rays per work-item must give every ray the same result as the single-ray kernels
// (Rays_Closest / Rays_Occluded over Wide_Query): the same closest t, bit for bit, and the same
// occlusion, with the watertight triangle test and with Moller-Trumbore, for coherent camera
// rays, shadow rays and incoherent random ones, and for a batch whose last packet is partial.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "bench/ray_batch.h"
#include "core/error.h"
#include "core/scene_loader.h"
#include "test_device.h"
#include "test_scenes.h"

namespace rt {
namespace {

using Accel = RenderOptions::Accel;

BatchRay unitRay(float ox, float oy, float oz, float dx, float dy, float dz, float tMax) {
    float l = std::sqrt(dx * dx + dy * dy + dz * dz);
    return {ox, oy, oz, tMax, dx / l, dy / l, dz / l, 0.f};
}

// Rays towards the scene's first mesh from `radii` bounding radii in front of it, in 8x8 tiles
// of a W x H grid (the order rtlab-trace-bench gives them), then `random` rays between random
// points around the mesh, whose directions differ from lane to lane; `drop` rays are left off
// the end, so that the last packet is partial.
std::vector<BatchRay> testRays(const Scene& s, int W, int H, int random, int drop) {
    const dev::MeshInstance& m = s.meshes.at(0);
    dev::Float3 c = m.sphereCenter;
    float r = m.sphereRadius;
    std::vector<BatchRay> rays;
    for (int ty = 0; ty < H; ty += 8)
        for (int tx = 0; tx < W; tx += 8)
            for (int y = ty; y < ty + 8; ++y)
                for (int x = tx; x < tx + 8; ++x) {
                    float u = (2.f * (float(x) + 0.5f) / float(W) - 1.f) * r;
                    float v = (2.f * (float(y) + 0.5f) / float(H) - 1.f) * r;
                    rays.push_back(unitRay(c.x, c.y, c.z - 2.f * r, u, v, 2.f * r, INFINITY));
                }
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> around(-1.5f, 1.5f);
    for (int i = 0; i < random; ++i) {
        float ox = c.x + around(rng) * r, oy = c.y + around(rng) * r, oz = c.z + around(rng) * r;
        float px = c.x + around(rng) * r, py = c.y + around(rng) * r, pz = c.z + around(rng) * r;
        rays.push_back(unitRay(ox, oy, oz, px - ox, py - oy, pz - oz, INFINITY));
    }
    rays.resize(rays.size() - size_t(drop));
    return rays;
}

// One shadow ray per hit, from just before the hit point towards a point above the mesh, ending
// there (finite tMax).
std::vector<BatchRay> shadowRays(const Scene& s, const std::vector<BatchRay>& rays,
                                 const std::vector<float>& t) {
    const dev::MeshInstance& m = s.meshes.at(0);
    dev::Float3 light{m.sphereCenter.x + m.sphereRadius, m.sphereCenter.y + 3.f * m.sphereRadius,
                      m.sphereCenter.z - m.sphereRadius};
    std::vector<BatchRay> shadow;
    for (size_t i = 0; i < rays.size(); ++i) {
        if (t[i] < 0.f) continue;
        float back = t[i] * 0.9999f;
        float px = rays[i].ox + back * rays[i].dx, py = rays[i].oy + back * rays[i].dy,
              pz = rays[i].oz + back * rays[i].dz;
        float dx = light.x - px, dy = light.y - py, dz = light.z - pz;
        float d = std::sqrt(dx * dx + dy * dy + dz * dz);
        shadow.push_back(unitRay(px, py, pz, dx, dy, dz, d));
    }
    return shadow;
}

// Every lane of a packet must matter: each lane position (ray index mod `packet`) holds rays
// that hit and rays that miss, so a lane whose hits were dropped, or kept from another lane,
// would change some ray's result below.
void expectEveryLaneHitsAndMisses(const std::vector<int>& hit, int packet, const char* what) {
    for (int lane = 0; lane < packet; ++lane) {
        int hits = 0, misses = 0;
        for (size_t i = size_t(lane); i < hit.size(); i += size_t(packet))
            (hit[i] ? hits : misses)++;
        EXPECT_GT(hits, 0) << what << ": lane " << lane << " of " << packet;
        EXPECT_GT(misses, 0) << what << ": lane " << lane << " of " << packet;
    }
}

// The packet kernels of both sizes against the single-ray kernels on `rays` and their shadow
// rays.
void expectPacketsMatchSingleRays(const Scene& scene, bool watertight,
                                  const std::vector<BatchRay>& rays) {
    RenderOptions o = scene.defaults;
    o.accel = Accel::Wide;
    o.watertight = watertight;
    ClContext& cl = test::device();
    BatchTracer single(cl, scene, o, 0, "wide");
    std::vector<float> t = single.closest(rays);
    std::vector<BatchRay> shadow = shadowRays(scene, rays, t);
    std::vector<int> blocked = single.occluded(shadow);

    std::vector<int> hit(t.size());
    for (size_t i = 0; i < t.size(); ++i) hit[i] = t[i] >= 0.f;
    size_t hits = std::count(hit.begin(), hit.end(), 1);
    size_t occluded = std::count(blocked.begin(), blocked.end(), 1);
    ASSERT_GT(hits, rays.size() / 10) << scene.name;
    ASSERT_LT(hits, rays.size() * 9 / 10) << scene.name;
    ASSERT_GT(occluded, shadow.size() / 20) << scene.name;
    ASSERT_LT(occluded, shadow.size() * 19 / 20) << scene.name;

    for (int packet : {8, 16}) {
        SCOPED_TRACE(scene.name + (watertight ? ", watertight" : ", Moller-Trumbore") +
                     ", packets of " + std::to_string(packet));
        expectEveryLaneHitsAndMisses(hit, packet, "primary");
        expectEveryLaneHitsAndMisses(blocked, packet, "shadow");
        BatchTracer packets(cl, scene, o, packet, "wide-p" + std::to_string(packet));
        std::vector<float> pt = packets.closest(rays);
        ASSERT_EQ(pt.size(), t.size());
        int differ = 0;
        for (size_t i = 0; i < t.size(); ++i)
            if (std::memcmp(&pt[i], &t[i], sizeof(float)) != 0 && differ++ < 5)
                ADD_FAILURE() << "ray " << i << ": packet t " << pt[i] << ", single " << t[i];
        EXPECT_EQ(differ, 0);
        std::vector<int> pb = packets.occluded(shadow);
        ASSERT_EQ(pb.size(), blocked.size());
        differ = 0;
        for (size_t i = 0; i < pb.size(); ++i)
            if (pb[i] != blocked[i] && differ++ < 5)
                ADD_FAILURE() << "shadow ray " << i << ": packet " << pb[i] << ", single "
                              << blocked[i];
        EXPECT_EQ(differ, 0);
    }
}

TEST(PacketTrace, BunnyRaysGetTheSingleRayResults) {
    const std::filesystem::path bunny = test::sharedFile("models/bunny.obj");
    RTLAB_REQUIRE_FILE(bunny);
    Scene scene = loadScene(bunny.string());
    scene.spheres.clear();
    scene.planes.clear();
    // 64 x 48 camera rays, 1000 random ones, the last packet 5 rays short.
    expectPacketsMatchSingleRays(scene, true, testRays(scene, 64, 48, 1000, 5));
}

TEST(PacketTrace, TriangleSoupRaysGetTheSingleRayResults) {
    Scene scene = test::soup(0, 4000, 11);
    for (bool watertight : {true, false})
        expectPacketsMatchSingleRays(scene, watertight, testRays(scene, 48, 48, 1500, 3));
}

TEST(PacketTrace, RefusesWhatThePacketKernelsCannotTrace) {
    ClContext& cl = test::device();
    Scene tris = test::soup(0, 50, 3);
    RenderOptions o = tris.defaults;
    o.accel = Accel::Bvh;
    try {
        BatchTracer t(cl, tris, o, 8, "bvh-p8");
        ADD_FAILURE() << "packets on the binary BVH were accepted";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), "--accels bvh-p8: packets traverse the wide BVH only");
    }
    o.accel = Accel::Wide;
    try {
        BatchTracer t(cl, tris, o, 12, "wide-p12");
        ADD_FAILURE() << "packets of 12 were accepted";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), "--accels wide-p12: packets hold 8 or 16 rays");
    }
    Scene mixed = test::soup(5, 50, 3);
    try {
        BatchTracer t(cl, mixed, o, 16, "wide-p16");
        ADD_FAILURE() << "a scene with spheres was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("triangles only"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace rt
