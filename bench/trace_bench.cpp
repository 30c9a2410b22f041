// rtlab-trace-bench — Embree as a peer inside the benchmark. Traces exactly the rays
// of a scene's camera (one primary ray per pixel centre, then one shadow ray per primary hit
// towards each light) through Embree on every CPU thread and through rtlab's structures on the
// OpenCL CPU device (PoCL), on the same cores, interleaved round by round, and reports rays/s
// side by side. Hit counts must agree: a ray that grazes a shared edge or the silhouette may hit
// in one and miss in the other (Embree's watertight test against rtlab's padded boxes and its own
// triangle test), so up to 0.01% of the rays of a batch (at least 2) may disagree; more ends in
// exit status 1. Both peers see the scene's triangles only (planes and spheres are dropped).
// Built without Embree (a GPU host), it times rtlab's structures alone, against the first one.
// An --accels entry wide-p8 or wide-p16 traces the wide BVH in packets of 8 or 16 rays per
// work-item (core/cl/accel_wide_packet.cl, for CPU devices); its results are also compared ray
// by ray with the single-ray wide kernels, which they must equal.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "bench/embree_peer.h"
#include "bench/measure.h"
#include "bench/ray_batch.h"
#include "bench/trace_visits.h"
#include "cli/parse_error.h"
#include "core/accel.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/kernel_resources.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "core/version.h"

namespace rt {
namespace {

// Primary rays in 8x8 tiles, the order both peers take them in chunks (coherent packets).
std::vector<BatchRay> primaryRays(const Scene& s, int W, int H) {
    const dev::Camera& c = s.camera;
    float D = 1.f / std::tan(c.fovY * 0.5f);
    float ca = std::cos(c.pitch), sa = std::sin(c.pitch), cb = std::cos(c.yaw),
          sb = std::sin(c.yaw);
    std::vector<BatchRay> rays;
    rays.reserve(size_t(W) * H);
    for (int ty = 0; ty < H; ty += 8)
        for (int tx = 0; tx < W; tx += 8)
            for (int y = ty; y < std::min(H, ty + 8); ++y)
                for (int x = tx; x < std::min(W, tx + 8); ++x) {
                    // core/cl/camera.cl, Camera_PrimaryRay, at the pixel centre.
                    float nx = (2.f * (float(x) + 0.5f) / float(W) - 1.f) * (float(W) / float(H));
                    float ny = 1.f - 2.f * (float(y) + 0.5f) / float(H);
                    float oy = ny * ca + D * sa, oz = D * ca - ny * sa;
                    float dx = nx * cb + oz * sb, dz = oz * cb - nx * sb;
                    float len = std::sqrt(dx * dx + oy * oy + dz * dz);
                    rays.push_back({c.position.x, c.position.y, c.position.z, INFINITY, dx / len,
                                    oy / len, dz / len, 0.f});
                }
    return rays;
}

// One shadow ray per hit and light, from the hit point lifted off the surface along the
// geometric normal (towards the viewer) by a millionth of the scene's size; back along the
// primary ray when there is no normal (no Embree). Light by light, each in the primary rays'
// tile order, so that consecutive rays (a packet, for Embree and rtlab alike) share a light.
std::vector<BatchRay> shadowRays(const Scene& s, const std::vector<BatchRay>& primary,
                                 const std::vector<float>& t,
                                 const std::vector<dev::Float3>& normal, float sceneSize) {
    std::vector<BatchRay> rays;
    float lift = 1e-6f * sceneSize;
    for (const dev::Light& l : s.lights)
        for (size_t i = 0; i < primary.size(); ++i) {
            if (t[i] < 0.f) continue;
            const BatchRay& r = primary[i];
            dev::Float3 n = normal.empty() ? dev::Float3{-r.dx, -r.dy, -r.dz} : normal[i];
            float nl = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
            float side = n.x * r.dx + n.y * r.dy + n.z * r.dz > 0.f ? -1.f : 1.f;
            float k = nl > 0.f ? side * lift / nl : 0.f;
            float px = r.ox + t[i] * r.dx + k * n.x, py = r.oy + t[i] * r.dy + k * n.y,
                  pz = r.oz + t[i] * r.dz + k * n.z;
            float dx = l.position.x - px, dy = l.position.y - py, dz = l.position.z - pz;
            float d = std::sqrt(dx * dx + dy * dy + dz * dz);
            if (d > 0.f) rays.push_back({px, py, pz, d, dx / d, dy / d, dz / d, 0.f});
        }
    return rays;
}

template <typename T>
std::vector<T> download(ClContext& cl, const cl::Buffer& b, size_t n) {
    std::vector<T> v(n);
    if (n) cl.queue().enqueueReadBuffer(b, CL_TRUE, 0, n * sizeof(T), v.data());
    return v;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

struct PeerResult {
    std::string name;
    double buildMs = 0;
    std::vector<double> primaryS, shadowS;
    std::vector<double> primaryDevS, shadowDevS;  // rtlab: the kernels' profiling-event time
    long long hits = 0, blocked = 0, primaryMismatch = 0, shadowMismatch = 0;
    std::map<std::string, double> resources;  // rtlab: registers, spills, private bytes per kernel
    // A packet peer: the single-ray peer of its structure, and the rays whose t (bit for bit) or
    // occlusion differs from it; -1 without one.
    std::string single;
    long long primaryVsSingle = -1, shadowVsSingle = -1;
};

// One --accels entry: a structure name (one ray per work-item) or wide-p8 / wide-p16 (packets
// of 8 or 16 rays per work-item, BatchTracer refuses other structures).
RenderOptions::Accel parsePeerEntry(const std::string& entry, int& packet) {
    size_t dash = entry.rfind("-p");
    packet = 0;
    if (dash == std::string::npos) return parseAccel(entry);
    std::string n = entry.substr(dash + 2);
    if (n.empty() || n.find_first_not_of("0123456789") != std::string::npos || n.size() > 3)
        throw Error("--accels " + entry + ": expected a structure, or wide-p8 / wide-p16");
    packet = std::stoi(n);
    return parseAccel(entry.substr(0, dash));
}

struct Args {
    std::string scene, size, accels = "bvh,wide,wide-p16", device = "cpu", out;
    int rounds = 5;
    int local = 0;
    int coherent = 1;  // rays per group that trace one ray (a bound on SIMT divergence)
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    double distance = 0;
    double pitch = 1000;  // degrees; 1000 keeps the scene's
};

// Puts the camera `radii` bounding radii from the mesh's centre, looking at it along its view.
void placeCamera(Scene& s, double radii) {
    const dev::MeshInstance& m = s.meshes.at(0);
    dev::Camera& c = s.camera;
    double fx = std::cos(c.pitch) * std::sin(c.yaw), fy = std::sin(c.pitch),
           fz = std::cos(c.pitch) * std::cos(c.yaw);
    double d = radii * m.sphereRadius;
    c.position = {float(m.sphereCenter.x - d * fx), float(m.sphereCenter.y - d * fy),
                  float(m.sphereCenter.z - d * fz)};
}

// The scene as both peers see it (triangles and lights), the camera where the flags put it.
Scene prepareScene(const Args& a, RenderOptions& o) {
    Scene scene = loadScene(a.scene);
    scene.spheres.clear();
    scene.planes.clear();
    if (scene.triangles.empty()) throw Error(a.scene + ": no triangles to trace");
    if (scene.lights.empty()) throw Error(a.scene + ": no light for the shadow rays");
    if (a.pitch != 1000) scene.camera.pitch = float(a.pitch * M_PI / 180.0);
    if (a.distance > 0) placeCamera(scene, a.distance);
    o = scene.defaults;
    if (!a.size.empty() && std::sscanf(a.size.c_str(), "%dx%d", &o.width, &o.height) != 2)
        throw Error("--size " + a.size + ": expected WxH");
    if (o.width < 1 || o.height < 1) throw Error("--size " + a.size + ": must be positive");
    return scene;
}

// Prints the table and the work per ray, writes the JSON when asked; false when hits disagree.
bool report(const Args& a, const Scene& scene, const RenderOptions& o, ClContext& cl,
            const EmbreePeer* embree, const std::vector<PeerResult>& peers,
            const std::vector<BatchRay>& primary, const std::vector<BatchRay>& shadow) {
    auto mrays = [](size_t n, const std::vector<double>& s) {
        double m = median(s);
        return m > 0 ? double(n) / m * 1e-6 : 0.0;
    };
    auto allowed = [](size_t n) { return std::max<long long>(2, (long long)(1e-4 * double(n))); };
    std::printf(
        "rtlab-trace-bench: %s, %dx%d, %zu primary rays (%.1f%% hit), %zu shadow rays to %zu "
        "light(s), %d rounds interleaved\n",
        scene.name.c_str(), o.width, o.height, primary.size(),
        100.0 * double(peers[0].hits) / double(primary.size()), shadow.size(), scene.lights.size(),
        a.rounds);
    std::printf(
        "rtlab on %s; %s\n\n", cl.device().label().c_str(),
        embree ? ("Embree " + embree->version() + " on " + std::to_string(a.threads) + " threads")
                     .c_str()
               : "built without Embree: ratios against the first structure");
    std::string versus = "x " + peers[0].name.substr(peers[0].name.find(' ') + 1);
    std::printf("%-15s %10s %14s %14s %10s %10s %9s %9s\n", "peer", "build ms", "primary Mray/s",
                "shadow Mray/s", "hits", "occluded", versus.c_str(), "mismatch");
    bool agree = true;
    std::string kernelOnly, sameAsSingle;
    nlohmann::json rows = nlohmann::json::array();
    double ep = mrays(primary.size(), peers[0].primaryS),
           es = mrays(shadow.size(), peers[0].shadowS);
    for (const PeerResult& p : peers) {
        double mp = mrays(primary.size(), p.primaryS), ms = mrays(shadow.size(), p.shadowS);
        bool ok = p.primaryMismatch <= allowed(primary.size()) &&
                  p.shadowMismatch <= allowed(shadow.size());
        agree = agree && ok;
        std::printf("%-15s %10.1f %14.2f %14.2f %10lld %10lld %4.2f/%4.2f %4lld/%lld%s\n",
                    p.name.c_str(), p.buildMs, mp, ms, p.hits, p.blocked, ep > 0 ? mp / ep : 0,
                    es > 0 ? ms / es : 0, p.primaryMismatch, p.shadowMismatch,
                    ok ? "" : "  DISAGREE");
        if (!p.primaryDevS.empty())
            kernelOnly += " " + p.name + " " +
                          std::to_string(mrays(primary.size(), p.primaryDevS)) + " / " +
                          std::to_string(mrays(shadow.size(), p.shadowDevS)) + ";";
        rows.push_back({{"peer", p.name},
                        {"build_ms", p.buildMs},
                        {"primary_mrays_per_s", mp},
                        {"shadow_mrays_per_s", ms},
                        {"primary_s", p.primaryS},
                        {"primary_mrays_per_s_device", mrays(primary.size(), p.primaryDevS)},
                        {"shadow_mrays_per_s_device", mrays(shadow.size(), p.shadowDevS)},
                        {"shadow_s", p.shadowS},
                        {"primary_hits", p.hits},
                        {"occluded", p.blocked},
                        {"primary_vs_reference", ep > 0 ? mp / ep : 0},
                        {"shadow_vs_reference", es > 0 ? ms / es : 0},
                        {"primary_mismatch", p.primaryMismatch},
                        {"shadow_mismatch", p.shadowMismatch},
                        {"kernel_resources", p.resources}});
        if (!p.single.empty()) {
            rows.back()["single_ray_peer"] = p.single;
            rows.back()["primary_t_differs_from_single_ray"] = p.primaryVsSingle;
            rows.back()["shadow_differs_from_single_ray"] = p.shadowVsSingle;
            sameAsSingle += " " + p.name + " vs " + p.single + ": " +
                            std::to_string(p.primaryVsSingle) + " primary t / " +
                            std::to_string(p.shadowVsSingle) + " shadow;";
        }
    }
    std::printf("kernel time only (profiling events), primary / shadow Mray/s:%s\n",
                kernelOnly.c_str());
    if (!sameAsSingle.empty())
        std::printf("rays whose result differs from the single-ray kernels:%s\n",
                    sameAsSingle.c_str());
    // What each kernel costs the device per work-item: on a GPU, registers bound occupancy.
    for (const PeerResult& p : peers) {
        if (p.resources.empty()) continue;
        std::printf("%s kernels:", p.name.c_str());
        for (const auto& [key, value] : p.resources) std::printf(" %s %g;", key.c_str(), value);
        std::printf("\n");
    }
    // The work behind the figures: what a ray does in each BVH, and the time per node visit
    // that rtlab's rays/s implies on the cores both peers share. The wide build keeps the binary
    // tree it collapses, over the same triangle order.
    AccelData wide = buildAccel(scene, RenderOptions::Accel::Wide);
    auto costJson = [&](const char* label, const TraversalCost& pc, const TraversalCost& sc) {
        std::printf(
            "%s, per ray (host count over %zu + %zu rays): primary %.1f nodes, %.1f "
            "triangles, %.0f B; shadow %.1f nodes, %.1f triangles, %.0f B\n",
            label, pc.rays, sc.rays, pc.nodes, pc.triangles, pc.bytes, sc.nodes, sc.triangles,
            sc.bytes);
        return nlohmann::json{
            {"primary_nodes_per_ray", pc.nodes},        {"primary_triangles_per_ray", pc.triangles},
            {"primary_bytes_per_ray", pc.bytes},        {"shadow_nodes_per_ray", sc.nodes},
            {"shadow_triangles_per_ray", sc.triangles}, {"shadow_bytes_per_ray", sc.bytes},
            {"rays_sampled", pc.rays + sc.rays}};
    };
    std::printf("\n");
    nlohmann::json bvhCost = costJson("binary BVH", binaryTraversalCost(wide, primary, false),
                                      binaryTraversalCost(wide, shadow, true));
    nlohmann::json cost = costJson("wide BVH", wideTraversalCost(wide, primary, false),
                                   wideTraversalCost(wide, shadow, true));
    buildCwbvh(wide);  // from the same binary tree
    nlohmann::json cwCost = costJson("cwbvh", cwbvhTraversalCost(wide, primary, false),
                                     cwbvhTraversalCost(wide, shadow, true));
    // What a packet of rays does instead (the packet peers' sizes), and how many of its rays
    // each node and triangle serves.
    nlohmann::json packetCost = nlohmann::json::object();
    std::vector<int> sizes;
    for (const PeerResult& p : peers)
        if (size_t at = p.name.rfind("-p"); at != std::string::npos)
            sizes.push_back(std::stoi(p.name.substr(at + 2)));
    std::sort(sizes.begin(), sizes.end());
    sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());
    for (int size : sizes) {
        PacketCost pc = widePacketTraversalCost(wide, primary, false, size);
        PacketCost sc = widePacketTraversalCost(wide, shadow, true, size);
        std::printf(
            "wide BVH, packets of %d (host count over %zu + %zu packets): primary %.1f "
            "nodes, %.1f triangles per packet, %.0f%% / %.0f%% of its rays served per node "
            "/ triangle; shadow %.1f nodes, %.1f triangles, %.0f%% / %.0f%%\n",
            size, pc.packets, sc.packets, pc.nodes, pc.triangles, 100 * pc.nodeLanes,
            100 * pc.triangleLanes, sc.nodes, sc.triangles, 100 * sc.nodeLanes,
            100 * sc.triangleLanes);
        packetCost["p" + std::to_string(size)] = {{"primary_nodes_per_packet", pc.nodes},
                                                  {"primary_triangles_per_packet", pc.triangles},
                                                  {"primary_node_lane_use", pc.nodeLanes},
                                                  {"primary_triangle_lane_use", pc.triangleLanes},
                                                  {"shadow_nodes_per_packet", sc.nodes},
                                                  {"shadow_triangles_per_packet", sc.triangles},
                                                  {"shadow_node_lane_use", sc.nodeLanes},
                                                  {"shadow_triangle_lane_use", sc.triangleLanes},
                                                  {"packets_sampled", pc.packets + sc.packets}};
    }
    if (!a.out.empty()) {
        nlohmann::json doc = bench::deviceJson(cl.device());
        doc.update(
            {{"bench", "trace-peer"},
             {"scene", scene.name},
             {"scene_file", a.scene},
             {"width", o.width},
             {"height", o.height},
             {"camera_radii", a.distance},
             {"camera_pitch_deg", scene.camera.pitch * 180.0 / M_PI},
             {"triangles", scene.triangles.size()},
             {"primary_rays", primary.size()},
             {"shadow_rays", shadow.size()},
             {"rounds", a.rounds},
             {"local_size", a.local},
             {"coherent_rays", a.coherent},
             // Which kernel sources ran: the embedded ones, or a tree ($RTLAB_KERNEL_DIR),
             // and any extra compiler options ($RTLAB_CL_OPTIONS), for A/B runs.
             {"kernel_sources",
              std::getenv("RTLAB_KERNEL_DIR") ? std::getenv("RTLAB_KERNEL_DIR") : "embedded"},
             {"cl_options", std::getenv("RTLAB_CL_OPTIONS") ? std::getenv("RTLAB_CL_OPTIONS") : ""},
             {"reference", peers[0].name},
             {"embree_version", embree ? embree->version() : "none"},
             {"embree_threads", embree ? a.threads : 0},
             {"agree", agree},
             {"peers", rows},
             {"bvh_cost", bvhCost},
             {"cwbvh_cost", cwCost},
             {"wide_cost", cost},
             {"wide_packet_cost", packetCost}});
        std::filesystem::create_directories(a.out);
        char radii[32] = "";
        if (a.distance > 0) std::snprintf(radii, sizeof radii, "-r%g", a.distance);
        std::string file = a.out + "/trace-" + scene.name + "-" + std::to_string(o.width) + "x" +
                           std::to_string(o.height) + radii + ".json";
        std::ofstream(file) << doc.dump(2) << "\n";
        std::printf("\nwrote %s\n", file.c_str());
    }
    return agree;
}

int run(const Args& a) {
    RenderOptions o;
    Scene scene = prepareScene(a, o);
    float sceneSize = 0;
    for (const dev::MeshInstance& m : scene.meshes) sceneSize = std::max(sceneSize, m.sphereRadius);

    // $RTLAB_KERNEL_DIR reads the kernels from a source tree, as in rtlab (no rebuild).
    const char* kernelDir = std::getenv("RTLAB_KERNEL_DIR");
    ClContext cl(selectDevice(a.device), KernelSources(kernelDir ? kernelDir : ""));
    std::unique_ptr<EmbreePeer> embree;
    std::vector<PeerResult> peers;
    if (EmbreePeer::available()) {
        embree = std::make_unique<EmbreePeer>(scene, a.threads);
        peers.push_back({"embree", embree->buildMs()});
    }
    const size_t off = peers.size();  // rtlab structure k is peers[off + k]
    std::vector<std::unique_ptr<BatchTracer>> rtlab;
    std::vector<RenderOptions::Accel> accels;
    std::string list = a.accels;
    for (size_t p = 0; p <= list.size();) {
        size_t q = std::min(list.find(',', p), list.size());
        std::string entry = list.substr(p, q - p);
        int packet = 0;
        o.accel = parsePeerEntry(entry, packet);
        rtlab.push_back(std::make_unique<BatchTracer>(cl, scene, o, packet, entry));
        accels.push_back(o.accel);
        std::string name = std::string("rtlab ") + accelName(o.accel);
        if (packet) name += "-p" + std::to_string(packet);
        peers.push_back({name, rtlab.back()->device().accelStats().buildMs});
        peers.back().resources =
            kernelResources(rtlab.back()->program(), cl.device().device, rtlab.back()->buildLog());
        p = q + 1;
    }

    // The reference hits (Embree's, else the first structure's) give the shadow rays.
    std::vector<BatchRay> primary = primaryRays(scene, o.width, o.height);
    // --coherent N: each run of N consecutive rays (a tile's) becomes copies of its middle ray,
    // for every peer. On a GPU, N = 32 makes each warp trace one ray 32 times: the kernel's rays/s
    // with no divergence at all, against which the real rays' figure measures what it costs.
    for (size_t i = 0, n = size_t(a.coherent); n > 1 && i < primary.size(); i += n) {
        BatchRay middle = primary[std::min(primary.size() - 1, i + n / 2)];
        std::fill(primary.begin() + long(i),
                  primary.begin() + long(std::min(primary.size(), i + n)), middle);
    }
    cl::Buffer primaryIn = uploadRays(cl, primary);
    cl::Buffer tOut(cl.context(), CL_MEM_WRITE_ONLY, primary.size() * 4);
    std::vector<float> t;
    std::vector<dev::Float3> normal;
    if (embree) {
        embree->intersect(primary, t, normal);
    } else {
        rtlab[0]->closest(primaryIn, tOut, primary.size(), a.local);
        t = download<float>(cl, tOut, primary.size());
    }
    std::vector<BatchRay> shadow = shadowRays(scene, primary, t, normal, sceneSize);
    cl::Buffer shadowIn = uploadRays(cl, shadow);
    cl::Buffer occOut(cl.context(), CL_MEM_WRITE_ONLY, std::max<size_t>(shadow.size(), 4) * 4);

    std::vector<int> blocked;
    std::vector<std::vector<float>> firstT(rtlab.size());  // round -1's results, peer by peer
    std::vector<std::vector<int>> firstBlocked(rtlab.size());
    for (int round = -1; round < a.rounds; ++round) {  // round -1 warms up and checks the hits
        double s = 0;
        if (embree) s = embree->intersect(primary, t, normal);
        if (embree && round >= 0) peers[0].primaryS.push_back(s);
        for (size_t k = 0; k < rtlab.size(); ++k) {
            s = rtlab[k]->closest(primaryIn, tOut, primary.size(), a.local);
            if (round >= 0) peers[off + k].primaryS.push_back(s);
            if (round >= 0) peers[off + k].primaryDevS.push_back(rtlab[k]->lastDeviceS());
            if (round >= 0) continue;
            firstT[k] = download<float>(cl, tOut, primary.size());
            for (size_t i = 0; i < primary.size(); ++i) {
                peers[off + k].hits += firstT[k][i] >= 0.f;
                peers[off + k].primaryMismatch += (firstT[k][i] >= 0.f) != (t[i] >= 0.f);
            }
        }
        if (embree) s = embree->occluded(shadow, blocked);
        if (embree && round >= 0) peers[0].shadowS.push_back(s);
        for (size_t k = 0; k < rtlab.size(); ++k) {
            if (shadow.empty()) break;
            s = rtlab[k]->occluded(shadowIn, occOut, shadow.size(), a.local);
            if (round >= 0) peers[off + k].shadowS.push_back(s);
            if (round >= 0) peers[off + k].shadowDevS.push_back(rtlab[k]->lastDeviceS());
            if (round >= 0) continue;
            firstBlocked[k] = download<int>(cl, occOut, shadow.size());
            if (!embree && k == 0) blocked = firstBlocked[k];  // the reference
            for (size_t i = 0; i < shadow.size(); ++i) {
                peers[off + k].blocked += firstBlocked[k][i];
                peers[off + k].shadowMismatch += firstBlocked[k][i] != blocked[i];
            }
        }
        if (embree && round < 0) {
            for (float x : t) peers[0].hits += x >= 0.f;
            for (int b : blocked) peers[0].blocked += b;
        }
    }
    // A packet peer against the single-ray kernels of its structure, ray by ray: the same t
    // (bit for bit) and the same occlusion are expected.
    for (size_t k = 0; k < rtlab.size(); ++k)
        for (size_t j = 0; j < rtlab.size(); ++j) {
            if (!rtlab[k]->packet() || rtlab[j]->packet() || accels[j] != accels[k]) continue;
            PeerResult& p = peers[off + k];
            p.single = peers[off + j].name;
            p.primaryVsSingle = p.shadowVsSingle = 0;
            for (size_t i = 0; i < primary.size(); ++i)
                p.primaryVsSingle += std::memcmp(&firstT[k][i], &firstT[j][i], 4) != 0;
            for (size_t i = 0; i < firstBlocked[k].size(); ++i)
                p.shadowVsSingle += firstBlocked[k][i] != firstBlocked[j][i];
            break;
        }

    if (!report(a, scene, o, cl, embree.get(), peers, primary, shadow)) {
        std::fprintf(stderr, "rtlab-trace-bench: hit counts disagree beyond 0.01%% of the rays\n");
        return 1;
    }
    return 0;
}

}  // namespace
}  // namespace rt

int main(int argc, char** argv) {
    rt::Args a;
    CLI::App app{"Embree as a peer: the same camera and shadow rays through Embree and rtlab"};
    app.set_version_flag("--version", std::string("rtlab-trace-bench ") + RTLAB_COMMIT,
                         "Print the commit this binary was built from and exit");
    app.add_option("scene", a.scene, "Scene file (.json) or a bare .obj")->required();
    app.add_option("--size", a.size, "Frame WxH [scene default]");
    app.add_option("--accels", a.accels,
                   "rtlab structures, comma-separated; wide-p8 / wide-p16: the wide BVH in "
                   "packets of 8 / 16 rays per work-item [bvh,wide,wide-p16]");
    app.add_option("--device", a.device, "OpenCL device for rtlab [cpu]");
    app.add_option("--rounds", a.rounds, "Timed rounds after one warm-up [5]")
        ->check(CLI::Range(1, 1000));
    app.add_option("--threads", a.threads, "Embree threads [every core]")
        ->check(CLI::Range(1, 4096));
    app.add_option("--distance", a.distance,
                   "Camera distance from the mesh's centre in bounding radii [scene camera]")
        ->check(CLI::PositiveNumber);
    app.add_option("--pitch", a.pitch,
                   "Camera pitch in degrees, -90 looks straight down, before --distance places it "
                   "[scene camera]")
        ->check(CLI::Range(-90.0, 90.0));
    app.add_option("--local", a.local, "Work-group size of rtlab's kernels [0: the driver's]")
        ->check(CLI::Range(0, 1024));
    app.add_option("--coherent", a.coherent,
                   "Replace each run of N consecutive primary rays (in 8x8 tiles) by copies of its "
                   "middle ray, for every peer: with N = 32 each GPU warp traces one ray, which "
                   "bounds what divergence costs [1: the camera's rays]")
        ->check(CLI::Range(1, 1 << 20));
    app.add_option("--out", a.out, "Folder for the JSON result [none]");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return rt::cli::reportParseError(app, e, "rtlab-trace-bench", argc, argv);
    }
    try {
        return rt::run(a);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab-trace-bench: %s\n", e.what());
        return 1;
    }
}
