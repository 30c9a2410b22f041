// rtlab — the report's wavefront pipeline (3.2.1 to 3.2.3): three kernels around a global ray tree
// of W x rows x N slots. Shadow rays are cast in trace and stored as occlusion counts in the node
// (4 bytes), so image does no ray casting: it only shades and mixes.
//
// The tree is stored so that each kernel touches only what it needs:
//   payloads  one Node (48 B) per slot, slot-major: slot i of the tile's P pixels is contiguous,
//             tree[i * P + pixel], so a work-group's same-slot reads and writes coalesce;
//   flags     one "traced" bit per slot, RT_TRACED_WORDS(N) words per pixel, also word-major,
//             traced[w * P + pixel]. They are the only truth about which slots hold a ray this
//             pass: payloads of other slots are stale, never cleared and never read.
// trace writes the payloads and bits of the slots it reaches; image walks from the root through
// the bits and reads only reached payloads; reset clears the bits alone (16-byte stores).
#include "raytree.cl"

// Where a pixel's slots and flag words live in the tile's buffers.
typedef struct WaveTree {
    size_t pixel;   // the pixel's index within the tile
    size_t pixels;  // P: the tile's pixel count, the stride from one slot (or word) to the next
} WaveTree;

// rowEnd: one past the tile's last row. GPU launches round the tile up to whole work-groups, and
// rows past the tile have no slots in the buffers.
inline WaveTree Wavefront_Tree(const RenderSettings* s, int x, int y, int rowEnd) {
    WaveTree t;
    t.pixel = (size_t)(y - s->rowOffset) * (size_t)s->width + (size_t)x;
    t.pixels = (size_t)(rowEnd - s->rowOffset) * (size_t)s->width;
    return t;
}

inline bool Wavefront_IsTraced(global const uint* traced, WaveTree t, int slot) {
    return (traced[(size_t)(slot >> 5) * t.pixels + t.pixel] >> (slot & 31)) & 1u;
}

// Traces the primary ray and every secondary ray of the pixel's tree for AA sample
// settings.sampleIndex, in heap order. A slot is traced when its parent was: the parent's bit
// comes from the word being built (same word) or from a stored one (earlier words; a word with
// no bit set is never stored, and reset has left it zero). A level with no traced slot ends the
// walk: nothing below it can be reached. In a deep tree the rest of a word of parents with no
// bit set is stepped over at once.
kernel void Wavefront_Trace(RT_SCENE_PARAMS, global Node* tree, global uint* traced, int rowEnd) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= rowEnd) return;
    RT_SCENE_INIT(sc);
    WaveTree t = Wavefront_Tree(&settings, x, y, rowEnd);
    tree[t.pixel] =
        RayTree_TraceNode(&sc, RayTree_PrimaryRay(&sc, x, y, settings.sampleIndex), RT_RAY_PRIMARY,
                          Sampling_PointKey(x, y, settings.sampleIndex, 0));
    uint word = 1u;  // bits of slots [32 * wordIndex, 32 * wordIndex + 32): the root so far
    int wordIndex = 0;
    uint parentWord = 0u;  // a stored word, cached: parents of a word's slots share one or two
    int parentWordIndex = -1;
    Node parent;  // cached: the C children of a parent are consecutive slots
    int parentSlot = -1;
    bool levelTraced = true;
    int levelEnd = 1;  // first slot of the next level
    const int nodes = RayTree_NodeCount(settings.bounces);
    for (int i = 1; i < nodes; ++i) {
        if (i == levelEnd) {
            if (!levelTraced) break;
            levelTraced = false;
            levelEnd = levelEnd * RT_BRANCH + 1;
        }
        if ((i >> 5) != wordIndex) {
            if (word) traced[(size_t)wordIndex * t.pixels + t.pixel] = word;
            word = 0u;
            wordIndex = i >> 5;
        }
        int p = (i - 1) / RT_BRANCH;
        uint bits = word;
        if ((p >> 5) != wordIndex) {
            if ((p >> 5) != parentWordIndex) {
                parentWordIndex = p >> 5;
                parentWord = traced[(size_t)parentWordIndex * t.pixels + t.pixel];
            }
            bits = parentWord;
        }
        if (!((bits >> (p & 31)) & 1u)) {
            // A deep tree (B >= 14 at C = 2): when no parent from p to the end of its word was
            // traced, skip to the first child of the next word's parents (or the level's end),
            // so that a level costs one step per word of parents rather than one per slot. In
            // shallower trees the test costs more than the slots it skips, so it is left out
            // there; `nodes` is the same for every work-item, so the branch does not diverge.
            if (nodes > 16383 && (bits >> (p & 31)) == 0u)
                i = min((((p >> 5) + 1) << 5) * RT_BRANCH + 1, levelEnd) - 1;
            continue;
        }
        if (p != parentSlot) {
            parent = tree[(size_t)p * t.pixels + t.pixel];  // written earlier by this work-item
            parentSlot = p;
        }
        Ray ray;
        if (RayTree_ChildRay(&sc, &parent, RayTree_Depth(p), i - 1 - p * RT_BRANCH, &ray)) {
            tree[(size_t)i * t.pixels + t.pixel] =
                RayTree_TraceNode(&sc, ray, RayTree_SlotType(i),
                                  Sampling_PointKey(x, y, settings.sampleIndex, RayTree_Depth(i)));
            word |= 1u << (i & 31);
            levelTraced = true;
        }
    }
    if (word) traced[(size_t)wordIndex * t.pixels + t.pixel] = word;
}

// One level of the image kernel's walk: a traced slot and what its children gave so far.
typedef struct WaveFrame {
    float3 refl, refr;  // colours of the reflection and refraction children, zero when untraced
    int slot;
    int next;  // the child slot (0..C-1) to visit next; C when all were visited
    int hasRefl, hasRefr;
} WaveFrame;

// The pixel's colour from its traced slots: a depth-first walk from the root that descends only
// into traced children and shades a node after its children (post-order), with the same
// RayTree_NodeColor call and inputs as RayTree_Combine's bottom-up loop over every slot, so the
// result is bit-identical to it. Untraced slots cost one bit test; their payloads are not read.
inline float3 Wavefront_Combine(const SceneData* sc, global const Node* tree,
                                global const uint* traced, WaveTree t) {
    // One frame per depth 0..B, sized for the largest B so that one program serves every bounce
    // limit; a walk touches only the first B + 1.
    WaveFrame stack[RT_MAX_BOUNCE_LIMIT + 1];
    const int nodes = RayTree_NodeCount(sc->settings.bounces);
    const float3 zero = (float3)(0.0f, 0.0f, 0.0f);
    int top = 0;
    stack[0].refl = stack[0].refr = zero;
    stack[0].slot = stack[0].next = stack[0].hasRefl = stack[0].hasRefr = 0;
    for (;;) {
        WaveFrame* f = &stack[top];
        if (f->next < RT_BRANCH) {
            int child = f->slot * RT_BRANCH + 1 + f->next++;
            if (child < nodes && Wavefront_IsTraced(traced, t, child)) {
                WaveFrame* c = &stack[++top];
                c->refl = c->refr = zero;
                c->slot = child;
                c->next = c->hasRefl = c->hasRefr = 0;
            }
            continue;
        }
        Node node = tree[(size_t)f->slot * t.pixels + t.pixel];
        float3 color =
            RayTree_NodeColor(sc, &node, f->hasRefl != 0, f->refl, f->hasRefr != 0, f->refr);
        if (top == 0) return color;
        WaveFrame* up = &stack[--top];
        if (up->next == 1) {
            up->hasRefl = 1;
            up->refl = color;
        } else {
            up->hasRefr = 1;
            up->refr = color;
        }
    }
}

// Combines the pixel's traced slots and accumulates the AA sample into the image: the first
// sample stores, later ones add, the last divides.
kernel void Wavefront_Image(RT_SCENE_PARAMS, global const Node* tree, global const uint* traced,
                            global float* image, int rowEnd) {
    int x = get_global_id(0), y = get_global_id(1) + settings.rowOffset;
    if (x >= settings.width || y >= rowEnd) return;
    RT_SCENE_INIT(sc);
    float3 c = Wavefront_Combine(&sc, tree, traced, Wavefront_Tree(&settings, x, y, rowEnd));
    int o = (y * settings.width + x) * 3;
    if (settings.sampleIndex > 0) c += (float3)(image[o], image[o + 1], image[o + 2]);
    int samples = settings.aaSamples * settings.aaSamples;
    if (settings.sampleIndex == samples - 1) c = c / (float)samples;
    image[o] = c.x;
    image[o + 1] = c.y;
    image[o + 2] = c.z;
}

// Clears the first `words` flag words, ready for the next pass: 16 bytes per work-item (the
// buffer is 16-byte aligned; a last partial group of four is cleared word by word).
kernel void Wavefront_Reset(global uint* traced, ulong words) {
    size_t first = get_global_id(0) * 4;
    if (first + 4 <= words) {
        ((global uint4*)traced)[get_global_id(0)] = (uint4)(0u);
    } else {
        for (size_t w = first; w < words; ++w) traced[w] = 0u;
    }
}
