// rtlab — the work one ray does in the binary and the wide BVH, counted on the host (see
// trace_visits.h). The box tests compute the entry distances as the device does (the wide one
// decodes the quantised boxes); the triangle test is Moller-Trumbore in double, which may differ
// from the device's on grazing rays only, so the counts are the device's up to those few rays.
#include "bench/trace_visits.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <utility>

#include "core/accel_quantize.h"

namespace rt {
namespace {

struct V3 {
    double x, y, z;
};
V3 sub(const dev::Float3& a, const dev::Float3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 cross(V3 a, V3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

double hitTriangle(const dev::Triangle& t, const BatchRay& r) {
    V3 d{r.dx, r.dy, r.dz};
    V3 e1 = sub(t.v1, t.v0), e2 = sub(t.v2, t.v0);
    V3 p = cross(d, e2);
    double det = dot(e1, p);
    if (det == 0) return -1;
    V3 s{r.ox - t.v0.x, r.oy - t.v0.y, r.oz - t.v0.z};
    double u = dot(s, p) / det;
    if (u < 0 || u > 1) return -1;
    V3 q = cross(s, e1);
    double v = dot(d, q) / det;
    if (v < 0 || u + v > 1) return -1;
    return dot(e2, q) / det;
}

// One triangle of a leaf: counts the test and shortens best to a closer hit; true when an any-hit
// query may stop there.
bool testTriangle(const dev::Triangle& t, const BatchRay& r, bool anyHit, float& best,
                  long long& tests) {
    ++tests;
    double h = hitTriangle(t, r);
    if (!(h > 0 && h < best)) return false;
    best = float(h);
    return anyHit;
}

// Entry distances of a node's four children, as Wide_Enter computes them.
void enter(const dev::WideNode& n, const BatchRay& r, const float inv[3], float tMax, float t[4]) {
    const float o[3] = {r.ox, r.oy, r.oz};
    const uint8_t* lo[3] = {n.loX, n.loY, n.loZ};
    const uint8_t* hi[3] = {n.hiX, n.hiY, n.hiZ};
    for (int k = 0; k < 4; ++k) {
        float near = 0.f, far = tMax;
        for (int a = 0; a < 3; ++a) {
            float step = quant::stepOf(n.exponent[a]);
            float base = ((&n.origin.x)[a] - o[a]) * inv[a], scale = step * inv[a];
            float t0 = float(lo[a][k]) * scale + base, t1 = float(hi[a][k]) * scale + base;
            near = std::max(near, std::min(t0, t1));
            far = std::min(far, std::max(t0, t1));
        }
        t[k] = n.child[k] != -1 && near <= far ? near : INFINITY;
    }
}

// Entry distance of a box, as Aabb_Enter computes it.
float enter(const dev::BvhNode& n, const BatchRay& r, const float inv[3], float tMax) {
    const float o[3] = {r.ox, r.oy, r.oz};
    float near = 0.f, far = tMax;
    for (int a = 0; a < 3; ++a) {
        float t0 = ((&n.lo.x)[a] - o[a]) * inv[a], t1 = ((&n.hi.x)[a] - o[a]) * inv[a];
        near = std::max(near, std::min(t0, t1));
        far = std::min(far, std::max(t0, t1));
    }
    return near <= far ? near : INFINITY;
}

void invDir(const BatchRay& r, float inv[3]) {
    const float d[3] = {r.dx, r.dy, r.dz};
    for (int a = 0; a < 3; ++a)
        inv[a] = 1.f / (std::fabs(d[a]) < 1e-20f ? std::copysign(1e-20f, d[a]) : d[a]);
}

// Calls trace(ray, inverse direction) for an even sample of at most maxRays of the batch;
// returns how many it followed.
template <typename Trace>
size_t forSampledRays(const std::vector<BatchRay>& rays, size_t maxRays, Trace trace) {
    size_t stride = std::max<size_t>(1, rays.size() / maxRays), followed = 0;
    for (size_t i = 0; i < rays.size(); i += stride, ++followed) {
        float inv[3];
        invDir(rays[i], inv);
        trace(rays[i], inv);
    }
    return followed;
}

}  // namespace

TraversalCost binaryTraversalCost(const AccelData& data, const std::vector<BatchRay>& rays,
                                  bool anyHit, size_t maxRays) {
    TraversalCost cost;
    if (data.bvh.empty() || rays.empty()) return cost;
    long long nodes = 0, pairs = 0, triangles = 0;
    cost.rays = forSampledRays(rays, maxRays, [&](const BatchRay& r, const float* inv) {
        float best = r.tMax;
        if (enter(data.bvh[0], r, inv, best) == INFINITY) {
            ++nodes;  // the root's box, tested on its own
            return;
        }
        int stack[64];
        float stackT[64];
        int top = 0, index = 0;
        for (bool done = false; !done;) {
            const dev::BvhNode& n = data.bvh[index];
            ++nodes;
            if (n.count == 0) {
                ++pairs;  // both children's records, one 64-byte fetch
                float ta = enter(data.bvh[n.first], r, inv, best);
                float tb = enter(data.bvh[n.first + 1], r, inv, best);
                bool swap = tb < ta;
                float tNear = swap ? tb : ta, tFar = swap ? ta : tb;
                if (tNear != INFINITY) {
                    if (tFar != INFINITY)
                        stack[top] = swap ? n.first : n.first + 1, stackT[top++] = tFar;
                    index = swap ? n.first + 1 : n.first;
                    continue;
                }
            } else {
                for (int p = n.first; p < n.first + n.count && !done; ++p) {
                    done = testTriangle(data.triangles[p], r, anyHit, best, triangles);
                }
                if (done) break;
            }
            while (top > 0 && !(stackT[top - 1] < best)) --top;
            if (top == 0) break;
            index = stack[--top];  // its (first, count) came with the stack entry: no load
        }
    });
    double n = double(cost.rays);
    cost.nodes = double(nodes) / n;
    cost.triangles = double(triangles) / n;
    cost.bytes = (32.0 * double(cost.rays) + 64.0 * double(pairs)) / n + 36 * cost.triangles;
    return cost;
}

TraversalCost wideTraversalCost(const AccelData& data, const std::vector<BatchRay>& rays,
                                bool anyHit, size_t maxRays) {
    TraversalCost cost;
    if (data.wide.empty() || rays.empty()) return cost;
    long long nodes = 0, triangles = 0;
    cost.rays = forSampledRays(rays, maxRays, [&](const BatchRay& r, const float* inv) {
        float best = r.tMax;
        int stack[64];
        float stackT[64];
        int top = 0, index = 0;
        bool done = false;
        while (!done) {
            const dev::WideNode& n = data.wide[index];
            ++nodes;
            float t[4];
            enter(n, r, inv, best, t);
            for (int k = 0; k < 4 && !done; ++k) {
                if (n.count[k] == 0 || !(t[k] < best) || (n.sphereMask >> k & 1)) continue;
                for (int p = n.child[k]; p < n.child[k] + n.count[k] && !done; ++p) {
                    done = testTriangle(data.triangles[p], r, anyHit, best, triangles);
                }
            }
            if (done) break;
            int near[4], m = 0;
            float nearT[4];
            for (int k = 0; k < 4; ++k) {
                if (n.count[k] != 0 || !(t[k] < best)) continue;
                int j = m++;
                for (; j > 0 && nearT[j - 1] > t[k]; --j)
                    near[j] = near[j - 1], nearT[j] = nearT[j - 1];
                near[j] = n.child[k], nearT[j] = t[k];
            }
            if (m > 0) {
                for (int j = m - 1; j > 0; --j) stack[top] = near[j], stackT[top++] = nearT[j];
                index = near[0];
                continue;
            }
            while (top > 0 && !(stackT[top - 1] < best)) --top;
            if (top == 0) break;
            index = stack[--top];
        }
    });
    cost.nodes = double(nodes) / double(cost.rays);
    cost.triangles = double(triangles) / double(cost.rays);
    cost.bytes = 64 * cost.nodes + 36 * cost.triangles;
    return cost;
}

TraversalCost cwbvhTraversalCost(const AccelData& data, const std::vector<BatchRay>& rays,
                                 bool anyHit, size_t maxRays) {
    TraversalCost cost;
    if (data.cwbvh.empty() || rays.empty()) return cost;
    long long nodes = 0, triangles = 0;
    cost.rays = forSampledRays(rays, maxRays, [&](const BatchRay& r, const float* inv) {
        const float o[3] = {r.ox, r.oy, r.oz};
        unsigned octant = (inv[0] < 0 ? 1u : 0u) | (inv[1] < 0 ? 2u : 0u) | (inv[2] < 0 ? 4u : 0u);
        float best = r.tMax;
        std::vector<std::pair<unsigned, unsigned>> stack;
        unsigned groupBase = 0, groupBits = 0;
        int index = 0;
        for (bool done = false; !done;) {
            const dev::CwbvhNode& n = data.cwbvh[size_t(index)];
            ++nodes;
            // Cwbvh_Enter: the facing bounds give the entry distances; empty slots never hit.
            const uint8_t* lo[3] = {n.loX, n.loY, n.loZ};
            const uint8_t* hi[3] = {n.hiX, n.hiY, n.hiZ};
            unsigned slots = 0;
            for (int k = 0; k < 8; ++k) {
                float near = 0.f, far = best;
                for (int a = 0; a < 3; ++a) {
                    float step = quant::stepOf(n.exponent[a]);
                    float base = ((&n.origin.x)[a] - o[a]) * inv[a], scale = step * inv[a];
                    const uint8_t* qn = inv[a] < 0 ? hi[a] : lo[a];
                    const uint8_t* qf = inv[a] < 0 ? lo[a] : hi[a];
                    near = std::max(near, std::fma(float(qn[k]), scale, base));
                    far = std::min(far, std::fma(float(qf[k]), scale, base));
                }
                if (near <= far) slots |= 1u << k;
            }
            unsigned entries = 0;
            for (int k = 0; k < 8; ++k)
                if ((slots & ~unsigned(n.innerMask)) >> k & 1)
                    entries |= ((2u << (n.meta[k] >> 5)) - 1u) << (n.meta[k] & 31);
            for (; entries && !done; entries &= entries - 1) {
                const dev::CwbvhPrim& p =
                    data.cwbvhPrims[size_t(n.primBase + std::countr_zero(entries))];
                if (p.ref < 0) continue;  // a sphere: not counted
                done = testTriangle(data.triangles[size_t(p.ref)], r, anyHit, best, triangles);
            }
            if (done) break;
            unsigned visit = 0;
            for (unsigned k = 0; k < 8; ++k)
                if ((slots & n.innerMask) >> k & 1) visit |= 1u << (k ^ octant);
            if (visit) {
                if (groupBits & 0xFF) stack.push_back({groupBase, groupBits});
                groupBase = unsigned(n.childBase);
                groupBits = visit | unsigned(n.innerMask) << 8;
            }
            if ((groupBits & 0xFF) == 0) {
                if (stack.empty()) break;
                std::tie(groupBase, groupBits) = stack.back();
                stack.pop_back();
            }
            unsigned k = unsigned(std::countr_zero(groupBits & 0xFF));
            groupBits &= ~(1u << k);
            unsigned slot = k ^ octant;
            index =
                int(groupBase + unsigned(std::popcount((groupBits >> 8) & ((1u << slot) - 1u))));
        }
    });
    cost.nodes = double(nodes) / double(cost.rays);
    cost.triangles = double(triangles) / double(cost.rays);
    cost.bytes = 80 * cost.nodes + 48 * cost.triangles;
    return cost;
}

PacketCost widePacketTraversalCost(const AccelData& data, const std::vector<BatchRay>& rays,
                                   bool anyHit, int P, size_t maxRays) {
    PacketCost cost;
    cost.size = P;
    if (data.wide.empty() || rays.empty() || P < 1 || P > 16) return cost;
    size_t packets = (rays.size() + size_t(P) - 1) / size_t(P);
    size_t stride = std::max<size_t>(1, packets / std::max<size_t>(1, maxRays / size_t(P)));
    long long nodes = 0, triangles = 0;
    double nodeLanes = 0, triangleLanes = 0;
    for (size_t pk = 0; pk < packets; pk += stride) {
        ++cost.packets;
        float inv[16][3], best[16];
        int lanes = 0;
        const BatchRay* r = rays.data() + pk * size_t(P);
        for (; lanes < P && pk * size_t(P) + size_t(lanes) < rays.size(); ++lanes) {
            invDir(r[lanes], inv[lanes]);
            best[lanes] = r[lanes].tMax;
        }
        auto live = [&] {
            for (int j = 0; j < lanes; ++j)
                if (best[j] > 0.f) return true;
            return false;
        };
        int stack[64], top = 0, index = 0;
        float stackT[64][16];
        for (;;) {
            const dev::WideNode& n = data.wide[index];
            ++nodes;
            float t[16][4];
            for (int j = 0; j < lanes; ++j) enter(n, r[j], inv[j], best[j], t[j]);
            for (int k = 0; k < 4 && live(); ++k) {
                int in = 0;  // rays that enter the leaf before their hit so far
                for (int j = 0; j < lanes; ++j) in += t[j][k] < best[j];
                if (n.count[k] == 0 || in == 0 || (n.sphereMask >> k & 1)) continue;
                for (int p = n.child[k]; p < n.child[k] + n.count[k] && live(); ++p) {
                    ++triangles;
                    triangleLanes += double(in) / P;
                    for (int j = 0; j < lanes; ++j) {
                        double h = hitTriangle(data.triangles[p], r[j]);
                        if (h > 0 && h < best[j]) best[j] = anyHit ? 0.f : float(h);
                    }
                }
            }
            if (!live()) break;
            int near[4], m = 0;
            float nearT[4], nearAll[4][16];
            for (int k = 0; k < 4; ++k) {
                if (n.count[k] != 0) continue;
                float key = INFINITY, all[16];
                for (int j = 0; j < lanes; ++j) {
                    all[j] = t[j][k] < best[j] ? t[j][k] : INFINITY;
                    key = std::min(key, all[j]);
                }
                if (key == INFINITY) continue;
                int j = m++;
                for (; j > 0 && nearT[j - 1] > key; --j) {
                    near[j] = near[j - 1], nearT[j] = nearT[j - 1];
                    std::copy(nearAll[j - 1], nearAll[j - 1] + lanes, nearAll[j]);
                }
                near[j] = n.child[k], nearT[j] = key;
                std::copy(all, all + lanes, nearAll[j]);
            }
            auto share = [&](const float* all) {
                int in = 0;
                for (int j = 0; j < lanes; ++j) in += all[j] < best[j];
                return double(in) / P;
            };
            if (m > 0) {
                for (int j = m - 1; j > 0; --j) {
                    stack[top] = near[j];
                    std::copy(nearAll[j], nearAll[j] + lanes, stackT[top++]);
                }
                index = near[0];
                nodeLanes += share(nearAll[0]);
                continue;
            }
            auto needed = [&](const float* all) {
                for (int j = 0; j < lanes; ++j)
                    if (all[j] < best[j]) return true;
                return false;
            };
            while (top > 0 && !needed(stackT[top - 1])) --top;
            if (top == 0) break;
            index = stack[--top];
            nodeLanes += share(stackT[top]);
        }
        nodeLanes += double(lanes) / P;  // the root: every ray of the packet
    }
    double n = double(cost.packets);
    cost.nodes = double(nodes) / n;
    cost.triangles = double(triangles) / n;
    cost.nodeLanes = nodes ? nodeLanes / double(nodes) : 0;
    cost.triangleLanes = triangles ? triangleLanes / double(triangles) : 0;
    return cost;
}

}  // namespace rt
