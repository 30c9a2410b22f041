// rtlab — records shared by the host (C++20) and the device (OpenCL C 1.2).
//
// This is the one definition of every struct that crosses the host/device boundary. The host
// compiles it inside namespace rt::dev; the OpenCL compiler sees it through the kernel-source
// include resolver (core/kernel_sources.cpp). Rules that keep the two layouts identical:
//   * only 4-byte scalars, 1/2-byte scalars packed into whole 4-byte words, and Float3;
//   * Float3 is three floats (12 bytes, 4-byte aligned), never OpenCL's float3 (16 bytes);
//   * every struct is padded by hand to a multiple of 16 bytes.
// Sizes are pinned by static_assert below and by tests/types_test.cpp, which asks the OpenCL
// compiler for the same sizeof and offsetof values.
#ifndef RTLAB_CORE_TYPES_H
#define RTLAB_CORE_TYPES_H

#ifdef __OPENCL_C_VERSION__
typedef int int32_t;
typedef uint uint32_t;
typedef ushort uint16_t;
typedef uchar uint8_t;
#define RT_DEV_BEGIN
#define RT_DEV_END
#else
#include <cstddef>
#include <cstdint>
#define RT_DEV_BEGIN namespace rt::dev {
#define RT_DEV_END }
#endif

RT_DEV_BEGIN

// Limits baked into the records. Scenes past them are rejected by the loader with a clear error.
#define RT_MAX_LIGHTS 16  // the most lights a scene may have
// Node keeps one occlusion count per light, RT_NODE_LIGHTS of them: a program is built with the
// scene's light count rounded up to a multiple of 4 (core/pipeline.cpp, featureDefines), and
// without the define, as every program of a scene of up to 4 lights is and as the host compiles
// this file, with 4 (a 48-byte Node). Host code sizes device buffers of Nodes with
// nodeBytes(lights) below, not sizeof.
#ifndef RT_NODE_LIGHTS
#define RT_NODE_LIGHTS 4
#endif
#define RT_MAX_SHADOW_SAMPLES 255  // ... in one byte
#define RT_MAX_MATERIALS 65535     // Node keeps the material in 16 bits
// The highest bounce limit B any front end, scene file or sweep accepts: a global ray tree at
// B=16 already needs 2^17 nodes per pixel of a transparent scene.
#define RT_MAX_BOUNCE_LIMIT 16

// Ray types: the device's ray counters (RT_COUNT_RAY) and the host's FrameStats::rays.
#define RT_RAY_PRIMARY 0
#define RT_RAY_REFLECTION 1
#define RT_RAY_REFRACTION 2
#define RT_RAY_SHADOW 3
#define RT_RAY_TYPES 4
// After the ray types, the counter buffer holds the warp counters of RT_COUNT_LANES programs
// (the megakernel's counting frame on NVIDIA): the active lanes summed over every warp step of
// the ray loop, and the warp steps.
#define RT_COUNT_LANES_ACTIVE RT_RAY_TYPES
#define RT_COUNT_WARP_STEPS (RT_RAY_TYPES + 1)
// Then RT_PHASES phase clocks, a diagnostic a pipeline's kernels may keep (the persistent
// schedules', built with RT_PERSIST_PHASE_CLOCKS on NVIDIA: persistent/phases.h names the slots):
// the cycles their warps spend in each phase, in units of 64, summed over warps.
#define RT_COUNT_PHASES (RT_RAY_TYPES + 2)
#define RT_PHASES 8
#define RT_COUNTERS (RT_RAY_TYPES + 2 + RT_PHASES)

typedef struct Float3 {
    float x, y, z;
} Float3;

// Blinn-Phong material with the report's reflection/transmission terms (section 3.5).
typedef struct Material {
    Float3 ambient;     // A, added unshadowed
    Float3 diffuse;     // D
    Float3 specular;    // S
    float exponent;     // E, Blinn-Phong exponent
    float reflectance;  // r in [0,1]: mirror weight for opaque materials
    float opacity;      // o in [0,1]: 1 = opaque, < 1 spawns a refraction ray
    float ior;          // refractive index of the inside of the object
    // Procedural diffuse colour (core/cl/procedural.cl); pattern 0 leaves D as it is.
    int32_t pattern;     // RT_PATTERN_*
    int32_t octaves;     // noise octaves (fBm, turbulence): the cost knob, 0..RT_MAX_OCTAVES
    float patternScale;  // noise lattice cells (checker squares) per unit length
    Float3 diffuse2;     // the pattern's second colour: D mixes toward it by the pattern value
    float bump;          // RT_PATTERN_BUMP: strength of the normal perturbation
} Material;

// Procedural patterns. Only scenes that use one compile them (RT_HAS_PROCEDURAL).
#define RT_PATTERN_NONE 0
#define RT_PATTERN_CHECKER 1
#define RT_PATTERN_MARBLE 2
#define RT_PATTERN_WOOD 3
#define RT_PATTERN_GRANITE 4
#define RT_PATTERN_BUMP 5
#define RT_PATTERN_ANY (-1)  // a shading caller that does not know the pattern: read it
#define RT_MAX_OCTAVES 64

typedef struct Sphere {
    Float3 center;
    float radius;
    int32_t material;
    int32_t pad[3];
} Sphere;

// Points p with dot(normal, p) == offset; normal is unit length.
typedef struct Plane {
    Float3 normal;
    float offset;
    int32_t material;
    int32_t pad[3];
} Plane;

// World-space triangle with per-vertex normals (computed by the loader when the OBJ has none).
typedef struct Triangle {
    Float3 v0, v1, v2;
    Float3 n0, n1, n2;
    int32_t material;
    int32_t mesh;  // index into the mesh instances; loose triangles share one implicit mesh
} Triangle;

// A contiguous run of triangles with its bounding volumes (box and sphere, section 2.2.2).
typedef struct MeshInstance {
    int32_t firstTriangle;
    int32_t triangleCount;
    int32_t bvhRoot;  // unused, -1: the BVH is one tree over every primitive
    int32_t pad0;
    Float3 boundsLo;
    Float3 boundsHi;
    Float3 sphereCenter;
    float sphereRadius;
    int32_t pad1[2];
} MeshInstance;

// Point light; radius > 0 makes it a disk light for soft shadows.
typedef struct Light {
    Float3 position;
    float radius;
    Float3 color;
    float pad;
} Light;

// Report eq. 12: yaw turns toward +x, positive pitch looks up; fovY in radians.
typedef struct Camera {
    Float3 position;
    float yaw;
    float pitch;
    float fovY;
    float pad[2];
} Camera;

// Uniform grid over the spheres and triangles (--accel grid): nx * ny * nz cells of
// cellSize over [lo, hi], x fastest. Zero cells when the scene has no sphere or triangle.
typedef struct Grid {
    Float3 lo;
    int32_t nx;
    Float3 hi;
    int32_t ny;
    Float3 cellSize;
    int32_t nz;
    Float3 invCellSize;
    int32_t pad;
} Grid;

// Everything a kernel needs besides the object arrays. Passed by value as a kernel argument.
typedef struct RenderSettings {
    int32_t width, height;
    int32_t bounces;        // B: the deepest node has depth B
    int32_t shadowSamples;  // rays per light for lights with radius > 0
    int32_t aaSamples;      // N: N x N sub-pixel samples
    int32_t sampleIndex;    // which sub-pixel sample this launch renders (AA in passes)
    int32_t sphereCount, planeCount, triangleCount, meshCount, lightCount, materialCount;
    float shadowStrength;  // fully occluded light keeps (1 - shadowStrength) of its contribution
    int32_t cubemapSize;   // face edge in texels; 0 = sky gradient
    int32_t rowOffset;     // first image row of this launch (tiling)
    Float3 skyZenith;
    Float3 skyHorizon;
    Float3 skyGround;
    Camera camera;
    Grid grid;  // filled by DeviceScene::setArgs, not by makeSettings
} RenderSettings;

// Node kinds: what the ray hit.
#define RT_KIND_MISS 0
#define RT_KIND_SPHERE 1
#define RT_KIND_PLANE 2
#define RT_KIND_TRIANGLE 3

// Node flags.
#define RT_NODE_TRACED 1u  // this slot holds a traced ray (trees in private memory; see below)
#define RT_NODE_INSIDE 2u  // the ray hit the surface from inside the object

// The report's wavefront (wavefront/tree) keeps its global tree's "traced" flags apart from the
// Node payloads, one bit per slot: RT_TRACED_WORDS(N) 32-bit words per pixel. Its reset kernel
// then clears N/8 bytes a pixel rather than a byte in every 48-byte node, and its image kernel
// reads a payload only where the bit is set; the payload's own RT_NODE_TRACED is not used there.
#define RT_TRACED_WORDS(nodes) (((nodes) + 31) / 32)

// One traced ray of a per-pixel ray tree, 48 bytes:
//   point    12  hit point (unused on a miss)
//   normal   12  shading normal, flipped to face the incoming ray
//   dir      12  incoming ray direction (the environment lookup on a miss)
//   object    4  index of the hit object within its kind
//   material  2  material index
//   kind      1  RT_KIND_*
//   flags     1  RT_NODE_*
//   occluded  4  occluded shadow samples per light (0..shadowSamples); RT_NODE_LIGHTS bytes
// Children of heap slot i live at i*C + 1 + k: k = 0 reflection, k = 1 refraction.
typedef struct Node {
    Float3 point;
    Float3 normal;
    Float3 dir;
    int32_t object;
    uint16_t material;
    uint8_t kind;
    uint8_t flags;
    uint8_t occluded[RT_NODE_LIGHTS];
} Node;

// BVH node. Inner node when count == 0: its children are nodes first and first + 1.
// Leaf of triangles [first, first + count) when count > 0, of spheres [first, first - count)
// when count < 0 (leaves hold one kind; the builder orders both arrays leaf by leaf).
typedef struct BvhNode {
    Float3 lo;
    int32_t first;
    Float3 hi;
    int32_t count;
} BvhNode;

// 4-wide BVH node (--accel wide; Ylitie, Karras and Laine 2017): the node's box is
// origin + [0, 255] * step per axis, step = 2^(exponent - 127) (a float's exponent bits, so the
// device decodes it with a shift). Child k's box is origin + [lo, hi] * step, rounded outward on
// the host, so it always contains the child's exact box. Child k is
//   an inner node:    count[k] == 0, child[k] = its node index;
//   a leaf:           count[k] > 0, child[k] = first primitive, spheres when bit k of sphereMask;
//   an empty slot:    child[k] == -1.
// 64 bytes: one cache line holds a node and the boxes of its four children.
typedef struct WideNode {
    Float3 origin;
    uint8_t exponent[3];
    uint8_t sphereMask;
    uint8_t loX[4], loY[4], loZ[4];
    uint8_t hiX[4], hiY[4], hiZ[4];
    int32_t child[4];
    uint16_t count[4];
} WideNode;

// Compressed 8-wide BVH node (--accel cwbvh; the layout of Ylitie, Karras and Laine
// 2017), 80 bytes: five 16-byte loads give the boxes of eight children. Boxes are quantised as in
// WideNode. Slot k's child lies towards corner k of the node (bit a of k set: the + side of axis
// a), so a ray whose direction has the sign bits o (bit a: towards -a) visits the slots in the
// order k ^ o, roughly nearest first, without sorting. Slot k is
//   an inner node: bit k of innerMask. The inner children are the nodes childBase, childBase + 1,
//                  ... in slot order.
//   a leaf:        meta[k] = offset | (count - 1) << 5, the entries prims[primBase + offset, +
//                  count) of CwbvhPrim; offset + count <= 32 (a node's leaves fit one 32-bit mask).
//   empty:         the quantised box lo = 255, hi = 0 on every axis, which no ray enters.
typedef struct CwbvhNode {
    Float3 origin;
    uint8_t exponent[3];
    uint8_t innerMask;
    int32_t childBase;
    int32_t primBase;
    uint8_t meta[8];
    uint8_t loX[8], loY[8], loZ[8];
    uint8_t hiX[8], hiY[8], hiZ[8];
} CwbvhNode;

// A primitive of a cwbvh leaf, laid out node by node so that a leaf's entries are adjacent:
// ref is a triangle t >= 0, whose vertices follow (the scene's floats, so that every hit is the
// one the other structures find), or a sphere ~s (the vertices unused). 48 bytes, three loads.
typedef struct CwbvhPrim {
    Float3 v0;
    int32_t ref;
    Float3 v1;
    float pad1;
    Float3 v2;
    float pad2;
} CwbvhPrim;

// Bounding volume of 7 slab pairs around a mesh (report 3.6.2, Kay and Kajiya 1986): slab k
// holds the points p with lo[k] <= dot(RT_SLAB_k, p) <= hi[k], for the unnormalized normals
// x, y, z, (1,1,1), (-1,1,1), (1,-1,1), (1,1,-1).
#define RT_SLABS 7
typedef struct Kdop {
    float lo[RT_SLABS];
    float hi[RT_SLABS];
    int32_t pad[2];
} Kdop;

RT_DEV_END

#ifndef __OPENCL_C_VERSION__
namespace rt::dev {
static_assert(sizeof(Float3) == 12 && alignof(Float3) == 4);
static_assert(sizeof(Material) == 80);
static_assert(offsetof(Material, diffuse2) == 64);
static_assert(sizeof(Sphere) == 32);
static_assert(sizeof(Plane) == 32);
static_assert(sizeof(Triangle) == 80);
static_assert(offsetof(Triangle, v1) == 12 &&
              offsetof(Triangle, v2) == 24);  // Hit_Triangle's loads
static_assert(sizeof(MeshInstance) == 64);
static_assert(sizeof(Light) == 32);
static_assert(sizeof(Camera) == 32);
static_assert(sizeof(RenderSettings) == 192);
static_assert(sizeof(Grid) == 64);
static_assert(sizeof(Kdop) == 64);
static_assert(sizeof(Node) == 48);
static_assert(sizeof(BvhNode) == 32);
static_assert(sizeof(WideNode) == 64);
static_assert(offsetof(WideNode, child) == 40);
static_assert(sizeof(CwbvhNode) == 80);
static_assert(offsetof(CwbvhNode, meta) == 24 && offsetof(CwbvhNode, loX) == 32);
static_assert(sizeof(CwbvhPrim) == 48 && offsetof(CwbvhPrim, ref) == 12);
static_assert(offsetof(Node, occluded) == 44);
static_assert(offsetof(RenderSettings, camera) == 96);
static_assert(offsetof(RenderSettings, grid) == 128);

// Occlusion counts a Node keeps in the programs of a scene of `lights` lights (RT_NODE_LIGHTS),
// and the device's size of a Node there: sizeof on the host is the 4-light record (records that
// hold a Node size themselves alike: wavefront/bounce/bounce_state.h).
constexpr int nodeLights(std::size_t lights) { return lights <= 4 ? 4 : int((lights + 3) / 4 * 4); }
constexpr std::size_t nodeBytes(std::size_t lights) {
    return sizeof(Node) - RT_NODE_LIGHTS + std::size_t(nodeLights(lights));
}
static_assert(nodeBytes(4) == 48 && nodeBytes(5) == 52 && nodeBytes(RT_MAX_LIGHTS) == 60);
}  // namespace rt::dev
#endif

#endif  // RTLAB_CORE_TYPES_H
