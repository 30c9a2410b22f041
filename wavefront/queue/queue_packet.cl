// rtlab — the queue wavefront's extend and shadow stages with ray packets (included
// by queue.cl under RT_QUEUE_PACKETS: CPU devices, --accel wide, no spheres outside the BVH).
// Both stages trace a compacted queue, so RT_PACKET consecutive entries make a packet: one
// work-item loads them, traces them together with Wide_QueryPacket (core/cl/accel_wide_packet.cl,
// vectorised across the rays by PoCL) and then finishes each ray exactly as the single-ray
// kernels do (RayTree_Surface, Shade_LightSamplesFrom). Every lane's hit is the one
// Scene_Intersect gives, so the image has the same bits as Queue_Extend and Queue_Shadow.
// Launches count items as before; a work-item covers RT_PACKET of them, and a launch's global
// offset is a multiple of RT_PACKET (QueueFrame::launch), so packets never straddle pieces.

// Scene_Query's planes, tested before the BVH as it does, one ray at a time: the plane hit
// below tMax (the closest, or with anyHit the first), or a miss with t = tMax.
inline Hit QueuePacket_Planes(const SceneData* sc, Ray ray, float tMax, bool anyHit) {
    Hit hit = Hit_None(tMax);
#ifdef RT_HAS_PLANES
    Scene_Planes(sc, ray, &hit, anyHit);
#else
    (void)sc;
    (void)ray;
    (void)anyHit;
#endif
    return hit;
}

// The rays of one packet, lane by lane, and each lane's hit so far (planes first). A lane with
// t = -INFINITY is unused; with anyHit, t = 0 marks a ray already occluded.
typedef struct PacketLanes {
    float o[3 * RT_PACKET], d[3 * RT_PACKET];  // x of every lane, then y, then z
    float t[RT_PACKET], u[RT_PACKET], v[RT_PACKET];
    int kind[RT_PACKET], object[RT_PACKET];
} PacketLanes;

inline void PacketLanes_Set(PacketLanes* l, int j, Ray ray, Hit hit) {
    l->o[j] = ray.origin.x;
    l->o[RT_PACKET + j] = ray.origin.y;
    l->o[2 * RT_PACKET + j] = ray.origin.z;
    l->d[j] = ray.dir.x;
    l->d[RT_PACKET + j] = ray.dir.y;
    l->d[2 * RT_PACKET + j] = ray.dir.z;
    l->t[j] = hit.t;
    l->u[j] = hit.uv.x;
    l->v[j] = hit.uv.y;
    l->kind[j] = hit.kind;
    l->object[j] = hit.object;
}

inline void PacketLanes_Unused(PacketLanes* l, int j) {
    Hit none;
    none.t = -INFINITY;
    none.kind = RT_KIND_MISS;
    none.object = -1;
    none.uv = (float2)(0.0f, 0.0f);
    PacketLanes_Set(l, j, makeRay((float3)(0.0f), (float3)(0.0f, 0.0f, 1.0f)), none);
}

// Traces the packet through the BVH below each lane's hit so far and writes the hits back.
inline void PacketLanes_Trace(const SceneData* sc, PacketLanes* l, bool anyHit) {
    RayPacket r = Packet_Make(l->o, l->d);
    PacketHit h;
    h.t = vloadP(0, l->t);
    h.u = vloadP(0, l->u);
    h.v = vloadP(0, l->v);
    h.kind = vloadP(0, l->kind);
    h.object = vloadP(0, l->object);
    Wide_QueryPacket(sc, &r, &h, anyHit);
    vstoreP(h.t, 0, l->t);
    vstoreP(h.u, 0, l->u);
    vstoreP(h.v, 0, l->v);
    vstoreP(h.kind, 0, l->kind);
    vstoreP(h.object, 0, l->object);
}

inline Hit PacketLanes_Hit(const PacketLanes* l, int j) {
    Hit hit;
    hit.t = l->t[j];
    hit.kind = l->kind[j];
    hit.object = l->object[j];
    hit.uv = (float2)(l->u[j], l->v[j]);
#ifdef RT_PACKET_DROP_LANE
    // Tests only: lose one lane's hit, which the packets-on-and-off test must notice.
    if (j == RT_PACKET_DROP_LANE) {
        hit.kind = RT_KIND_MISS;
        hit.object = -1;
    }
#endif
    return hit;
}

// From: pool [RT_PACKET g, RT_PACKET (g + 1)) of [0, n) / To: as Queue_Extend, ray by ray.
kernel void Queue_ExtendPacket(RT_SCENE_PARAMS, QUEUE_RAYS_PARAMS(rays), int n, global Node* nodes,
                               global int* shadeQueues, int pool, global int* shadowQueue,
                               global int* counters, int nWord, global uint* rayTally) {
    QUEUE_LOCAL_PAD();
    local int count[RT_Q_PUSHES], base[RT_Q_PUSHES];
    local int histogram[RT_Q_DEPTH_CLASSES];  // RT_Q_EXTEND_LOCAL_INTS in all
    int lid = get_local_id(0), size = get_local_size(0), g = get_global_id(0);
    int first = g * RT_PACKET;
    n = Queue_Length(n, nWord, counters);
    if ((g - lid) * RT_PACKET >= n) return;  // a whole group past the queue (Queue_Extend)
    Queue_GroupPushesBegin(count, histogram, lid, size);
    int lanes = clamp(n - first, 0, RT_PACKET);
    int queue[RT_PACKET], slot[RT_PACKET], shadowSlot[RT_PACKET];
    if (lanes > 0) {
        RT_SCENE_INIT(sc);
        QUEUE_RAYS_INIT(rays);
        PacketLanes l;
        for (int j = 0; j < RT_PACKET; ++j) {
            if (j >= lanes) {
                PacketLanes_Unused(&l, j);
                continue;
            }
            Pending p = Queue_Load(&rays, first + j);
            QUEUE_COUNT_RAY(rayTally, rays.pixel[first + j], p.type);
            PacketLanes_Set(&l, j, p.ray, QueuePacket_Planes(&sc, p.ray, INFINITY, false));
        }
        PacketLanes_Trace(&sc, &l, false);
        for (int j = 0; j < lanes; ++j) {
            int i = first + j;
            Pending p = Queue_Load(&rays, i);
            Node node = RayTree_Surface(&sc, p.ray, PacketLanes_Hit(&l, j));
            nodes[i] = node;
            int c = Queue_Class(&sc, &node);
            queue[j] = Queue_ShadeQueue(&sc, &node, c);
            slot[j] = atomic_inc(&count[queue[j]]);
            atomic_inc(&histogram[p.depth * RT_Q_CLASSES + c]);
            shadowSlot[j] =
                c != RT_Q_MISS && settings.lightCount > 0 ? atomic_inc(&count[RT_Q_QUEUES]) : -1;
        }
    }
    Queue_GroupPushesReserve(count, base, histogram, counters, lid, size);
    for (int j = 0; j < lanes; ++j) {
        shadeQueues[queue[j] * pool + base[queue[j]] + slot[j]] = first + j;
        if (shadowSlot[j] >= 0) shadowQueue[base[RT_Q_QUEUES] + shadowSlot[j]] = first + j;
    }
}

// From: shadow queue [RT_PACKET g, RT_PACKET (g + 1)), pool / To: nodes[i].occluded, as
// Queue_Shadow: sample k of light j of every lane goes in one packet.
kernel void Queue_ShadowPacket(RT_SCENE_PARAMS, global Node* nodes, global const int* shadowQueue,
                               global const int* counters, global const int* rayPixel,
                               global const int* rayMeta, global uint* rayTally) {
    QUEUE_LOCAL_PAD();
    int first = get_global_id(0) * RT_PACKET;
    int lanes = min(counters[RT_Q_SHADOW] - first, RT_PACKET);
    if (lanes <= 0) return;
    RT_SCENE_INIT(sc);
    int index[RT_PACKET], pixel[RT_PACKET];
    float3 point[RT_PACKET], normal[RT_PACKET], origin[RT_PACKET];
    uint key[RT_PACKET];
    for (int j = 0; j < lanes; ++j) {
        int i = shadowQueue[first + j];
        Node node = nodes[i];
        index[j] = i;
        point[j] = f3(node.point);
        normal[j] = f3(node.normal);
        origin[j] = RayTree_SpawnOrigin(&sc, &node, 1.0f);
        pixel[j] = rayPixel[i];
        int y = pixel[j] / settings.width, x = pixel[j] - y * settings.width;
        key[j] = Sampling_PointKey(x, y, settings.sampleIndex, rayMeta[i] >> 8);
    }
    for (int light = 0; light < settings.lightCount; ++light) {
        LightSamples s[RT_PACKET];
        int occluded[RT_PACKET], most = 0;
        for (int j = 0; j < lanes; ++j) {
            s[j] = Shade_LightSamplesFrom(&sc, point[j], normal[j], light, key[j]);
            most = max(most, s[j].count);
            occluded[j] = 0;
        }
        for (int k = 0; k < most; ++k) {
            PacketLanes l;
            for (int j = 0; j < RT_PACKET; ++j) {
                if (j >= lanes || k >= s[j].count) {
                    PacketLanes_Unused(&l, j);
                    continue;
                }
                // Shade_OcclusionFrom's ray, and Scene_Query's planes before the BVH.
                float3 v = Shade_LightPoint(&s[j], key[j], light, k) - origin[j];
                float len = length(v);
                QUEUE_COUNT_RAY(rayTally, pixel[j], RT_RAY_SHADOW);
                Ray ray = makeRay(origin[j], v / len);
                Hit hit = QueuePacket_Planes(&sc, ray, len, true);
                if (hit.kind != RT_KIND_MISS) hit.t = 0.0f;  // occluded: traced no further
                PacketLanes_Set(&l, j, ray, hit);
            }
            PacketLanes_Trace(&sc, &l, true);
            for (int j = 0; j < lanes; ++j)
                if (k < s[j].count && PacketLanes_Hit(&l, j).kind != RT_KIND_MISS) ++occluded[j];
        }
        for (int j = 0; j < lanes; ++j) nodes[index[j]].occluded[light] = (uchar)occluded[j];
    }
}
