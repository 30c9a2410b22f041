// rtlab — the persistent megakernel's regrouped loop (--persistent-schedule regrouped;
// RT_PERSIST_REGROUP is the work-group size): the flat loop (flat.cl) with each step cut in two
// at the hit. Every lane traces its own ray; then the work-group sorts the hits by pattern in
// local memory (a miss and an idle lane are two more keys), and lane i shades the i-th hit of that
// order, whoever's it is, so that the lanes of a warp run one shading path together instead of
// one after the other (a software form of shader execution reordering). The owner takes back the
// result and sums and pushes it exactly as Megakernel_TraceNext does: a pixel's terms arrive in
// the same order and each is computed by the same code from the same bits, so the image stays the
// weighted megakernel's. Each lane takes a pixel as soon as it has none.
#include "handout.cl"

#define RG_LANES RT_PERSIST_REGROUP

// A lane's slot in local memory holds a hit to shade, then what shading it gave: lane i copies
// slot i's hit into registers before it writes slot i's result, and no other lane touches slot i
// between the two barriers, so one array serves both. kRegroupSlotBytes (schedules.cpp) is the
// size of this union.
typedef struct RegroupHit {
    Node node;
    Pending p;
} RegroupHit;

typedef struct RegroupShade {
    float3 term;
    Pending refl, refr;
    int children;  // bit 0: refl, bit 1: refr
} RegroupShade;

typedef union RegroupSlot {
    RegroupHit hit;
    RegroupShade shade;
} RegroupSlot;

// Shades one traced ray: its term and the children it spawns.
inline RegroupShade Regroup_Shade(const SceneData* sc, const Node* n, const Pending* q) {
    RegroupShade s;
    s.children = 0;
    if (n->kind == RT_KIND_MISS) {
        s.term = PathState_Miss(sc, q);
    } else {
        bool hasRefl, hasRefr;
        s.term = PathState_Step(sc, n, q, true, true, RT_PATTERN_ANY, &s.refl, &hasRefl, &s.refr,
                                &hasRefr);
        s.children = (hasRefl ? 1 : 0) | (hasRefr ? 2 : 0);
    }
    return s;
}

kernel RT_GROUP_LANES(RG_LANES) void Persistent_RenderRegrouped(RT_SCENE_PARAMS,
                                                                global float* image,
                                                                global int* next, int first,
                                                                int count) {
    RT_SCENE_INIT(sc);
    local RegroupSlot slots[RG_LANES];
    // Key counts, three sets in turn, so that a step needs no barrier before it counts: it
    // zeroes the next step's set, last read two steps back, which every lane has left once it
    // passed the last step's barriers.
    local int keys[3][RG_KEYS];
    const int lane = (int)get_local_id(0);
    const int samples = settings.aaSamples * settings.aaSamples;
    RT_STACK_RECORD stack[RT_STACK_SIZE];
    int top = 0;
    PersistentLane l;
    l.pixel = -1;
    bool drained = false;  // the counter has no pixel left for this lane
    if (lane < RG_KEYS) keys[0][lane] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    PhaseClock phases = Phase_Start(lane, RG_LANES);
    for (int step = 0;; step = step == 2 ? 0 : step + 1) {
        Persistent_EndOfTree(&sc, image, &l, stack, &top, samples);
        if (l.pixel < 0 && !drained) {
            const int k = atomic_inc(next);
            if (k >= count)
                drained = true;
            else
                Persistent_Begin(&sc, &l, stack, &top, k, first, count);
        }
        PHASE_MARK(&sc, RT_PHASE_BOOKKEEPING, &phases);
        local int* counts = keys[step];
        if (lane < RG_KEYS) keys[step == 2 ? 0 : step + 1][lane] = 0;

        // Trace this lane's ray and count its hit under its key.
        Pending p;
        Node node;
        int key = RG_IDLE;
        if (l.pixel >= 0) {
            RT_COUNT_WARP_STEP(&sc);  // the lanes that trace a ray this step
            p = RT_STACK_POP(stack[--top]);
            node = RayTree_TraceNode(&sc, p.ray, p.type,
                                     Sampling_PointKey(l.xy.x, l.xy.y, l.sample, p.depth));
            key = Regroup_KeyOf(&sc, &node);
        }
        const int rank = atomic_inc(&counts[key]);
        PHASE_MARK(&sc, RT_PHASE_TRACE, &phases);
        barrier(CLK_LOCAL_MEM_FENCE);
        PHASE_MARK(&sc, RT_PHASE_TRACE_WAIT, &phases);
        // The whole work-group leaves together, once none of its lanes holds a ray: every lane
        // must reach every barrier.
        if (counts[RG_IDLE] == RG_LANES) break;

        // File the hit at its place in key order.
        int slot = rank, busy = 0;
        for (int k = 0; k < RG_IDLE; ++k) {
            if (k < key) slot += counts[k];
            busy += counts[k];
        }
        if (l.pixel >= 0) {
            slots[slot].hit.node = node;
            slots[slot].hit.p = p;
        }
        barrier(CLK_LOCAL_MEM_FENCE);
        PHASE_MARK(&sc, RT_PHASE_FILE, &phases);

        // Shade the lane-th hit of that order.
        if (lane < busy) {
            const Node n = slots[lane].hit.node;
            const Pending q = slots[lane].hit.p;
            slots[lane].shade = Regroup_Shade(&sc, &n, &q);
        }
        PHASE_MARK(&sc, RT_PHASE_SHADE, &phases);
        barrier(CLK_LOCAL_MEM_FENCE);
        PHASE_MARK(&sc, RT_PHASE_SHADE_WAIT, &phases);

        // Take back this lane's own result, in Megakernel_TraceNext's order.
        if (l.pixel >= 0) {
            const RegroupShade s = slots[slot].shade;
            l.color += s.term;
            if (s.children & 2) stack[top++] = RT_STACK_PUSH(s.refr);
            if (s.children & 1) stack[top++] = RT_STACK_PUSH(s.refl);
        }
    }
}
