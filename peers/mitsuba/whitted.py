#!/usr/bin/env python3
"""rtlab's Whitted image (core/SHADING.md) rendered by Mitsuba 3 / Dr.Jit: the peer of issue 53.

Mitsuba does the ray tracing (its scene, its BVH: OptiX on `cuda_ad_rgb`, Embree on
`llvm_ad_rgb`); the shading is rtlab's, written here as one Dr.Jit loop over each pixel's ray tree:
the same pinhole camera (section 1), procedural materials (5, through dr.switch), Blinn-Phong with
ambient (5), hard shadows from point lights and rtlab's jittered disk samples for lights of
non-zero radius (4), mirror reflection and refraction with Fresnel and total internal reflection
(6, 7), the same bounce limit B and the same children, combined as section 8 says, and the sky
gradient or cubemap (9). Secondary rays start where section 3 (bound) puts them.

The ray tree is walked depth first with the *weighted* formulation of section 8: a node adds
w (1 - F) o base to the pixel and hands w F to its reflection child and w (1 - F)(1 - o) to its
refraction child; the lane continues with one child and pushes the other onto a per-lane stack of
B entries (dr.alloc_local). The very same code runs in both of Dr.Jit's modes:

  symbolic   (default flags): the loop, the shape calls and the traces compile into ONE kernel
             per frame: a megakernel.
  evaluated  (JitFlag.SymbolicLoops and SymbolicCalls off): every loop iteration is launched
             separately and its state goes through device memory: a wavefront, one bounce (one
             tree node per lane) per step, finished lanes kept and masked (Dr.Jit's default).
             JitFlag.CompressLoops, which would drop them as rtlab's queue pipeline does, is not
             offered: in Dr.Jit 1.5 it fails on a loop with local memory (the LLVM backend's IR
             does not parse: "use of undefined value") and needs every per-lane array the body
             reads in the loop state.

Scene conversion (rtlab_scene.py reads the JSON): triangles merged into one mi.Mesh per material
(per-corner vertices, so rtlab's per-corner normals carry over); all spheres as ONE `ellipsoids`
shape (Mitsuba's analytic ellipsoid primitive, scales r, r, r, extent 1; per-sphere material by
primitive index), or with --spheres shapes one `sphere` shape each (the naive conversion the issue
measured); planes as `rectangle` shapes of half-size 1e4 x the scene's radius. Where the peer
departs from plain Mitsuba to compute rtlab's image (the ellipsoid's back faces and precision,
the offsets, the hit points) is said where it happens and in README.md.

Usage:
  whitted.py SCENE.json [--size WxH] [--bounces B] [--variant llvm_ad_rgb|cuda_ad_rgb]
             [--mode symbolic|evaluated] [-o out.exr|out.png|out.npy] [--stats]
"""
import argparse
import copy
import dataclasses
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rtlab_scene import NotConverted, Scene  # noqa: E402

MODES = ("symbolic", "evaluated")
GOLDEN = 2.399963229728653
TWO_PI = 6.283185307179586
PER_PRIM = 0xFFFFFFFF  # shape table entry: the material comes from the primitive (spheres)
NONE = 0xFFFFFFFF  # a ray inside no sphere
SPHERES = ("ellipsoids", "hybrid", "shapes")

mi = dr = None


def setup(variant):
    """Imports Mitsuba with `variant`. LLVM variants need libLLVM 15 or newer, which Dr.Jit
    finds by itself where the system has it (Debian: libllvm15, a dependency of PoCL), or
    DRJIT_LIBLLVM_PATH names it."""
    global mi, dr
    import drjit as _dr
    import mitsuba as _mi
    _mi.set_variant(variant)
    mi, dr = _mi, _dr
    return mi, dr


def set_mode(mode):
    """Dr.Jit's flags for one of MODES (global: they decide how the loop below compiles)."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode}")
    sym = mode == "symbolic"
    dr.set_flag(dr.JitFlag.SymbolicLoops, sym)
    dr.set_flag(dr.JitFlag.SymbolicCalls, sym)
    dr.set_flag(dr.JitFlag.CompressLoops, False)


# ---- scene conversion ------------------------------------------------------------------------

def _mesh(name, P, N):
    """One mi.Mesh from triangles P (T,3,3) and corner normals N (T,3,3): 3 vertices a triangle."""
    T = len(P)
    m = mi.Mesh(name, 3 * T, T, has_vertex_normals=True)
    params = mi.traverse(m)
    params["vertex_positions"] = mi.Float(P.astype(np.float32).ravel())
    params["vertex_normals"] = mi.Float(N.astype(np.float32).ravel())
    params["faces"] = mi.UInt32(np.arange(3 * T, dtype=np.uint32))
    params.update()
    return m


def _frame_to(n):
    """A rotation (3x3) taking +z to unit vector n."""
    z = np.asarray(n, dtype=np.float64)
    a = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


class Converted:
    """The Mitsuba scene of an rtlab scene, and the tables the integrator reads."""

    def __init__(self, sc, spheres="ellipsoids"):
        t0 = time.perf_counter()
        # Mitsuba 3.9's ellipsoid test starts its quadratic from the point at t = dot(c - o, d)
        # / r instead of / r^2 (ellipsoids.cpp, ray_ellipsoid_intersection: `plane_t = dot(-o, d)
        # / norm(d)` in the unit sphere's frame): exact for radius 1, and for a sphere of radius
        # 0.05 ten units away it reports hits out to 1.5 r. The peer therefore renders the scene
        # scaled by the power of two that brings the median sphere radius nearest to 1 (the
        # image is the same: see Scene.scale).
        self.scale = 1.0
        if len(sc.sphere_radius) and spheres != "shapes":
            self.scale = float(2.0 ** -np.round(np.log2(np.median(sc.sphere_radius))))
            if self.scale != 1.0:
                sc = copy.deepcopy(sc)
                sc.scale(self.scale)
        self.sc = sc
        d = {"type": "scene"}
        owner = {}  # dict key -> material index (or PER_PRIM)
        tri_abs, tri_base = [], {}
        for m, (P, N) in sorted(sc.triangles.items()):
            d[f"mesh{m}"] = _mesh(f"mesh{m}", P, N)
            owner[f"mesh{m}"] = m
            tri_base[f"mesh{m}"] = sum(len(x) for x in tri_abs)
            tri_abs.append(np.abs(P.astype(np.float32)).sum(axis=1))  # |v0| + |v1| + |v2|
        ns = len(sc.sphere_radius)
        # Mitsuba's `ellipsoids` culls back faces (it is made for volumetric primitives): a ray
        # that starts inside one never hits it, and rays start inside a sphere when it refracts.
        #   ellipsoids: every sphere in one `ellipsoids` shape; the integrator tracks the sphere a
        #               ray is inside and intersects it analytically (its exit), beside the trace.
        #   hybrid:     opaque spheres in one `ellipsoids` shape, transparent ones one `sphere`
        #               shape each (Mitsuba's analytic sphere, hit from both sides).
        #   shapes:     one `sphere` shape per sphere (the naive conversion of the issue).
        if spheres not in SPHERES:
            raise ValueError(f"spheres must be one of {', '.join(SPHERES)}, got {spheres}")
        transparent = np.array([sc.materials[m]["opacity"] < 1 for m in sc.sphere_material],
                               dtype=bool)
        together = {"ellipsoids": np.ones(ns, dtype=bool), "hybrid": ~transparent,
                    "shapes": np.zeros(ns, dtype=bool)}[spheres]
        if ns and (np.linalg.norm(sc.sphere_center - sc.position, axis=1)
                   < sc.sphere_radius).any():
            raise NotConverted(f"{sc.path}: the camera is inside a sphere (Mitsuba's ellipsoids "
                               f"cull back faces, and the peer starts every ray outside)")
        if together.any():
            r = sc.sphere_radius[together].astype(np.float32)
            k = len(r)
            d["spheres"] = {"type": "ellipsoids", "extent": 1.0,
                            "centers": mi.TensorXf(sc.sphere_center[together].astype(np.float32)),
                            "scales": mi.TensorXf(np.stack([r, r, r], axis=1)),
                            "quaternions": mi.TensorXf(np.tile(np.float32([1, 0, 0, 0]), (k, 1)))}
            owner["spheres"] = PER_PRIM
        for i in np.nonzero(~together)[0]:
            d[f"sphere{i}"] = {"type": "sphere", "center": sc.sphere_center[i].tolist(),
                               "radius": float(sc.sphere_radius[i])}
            owner[f"sphere{i}"] = int(sc.sphere_material[i])
        self.sphere_shapes = int((~together).sum())
        # The integrator's own test of the sphere a ray is inside (ellipsoids with glass only).
        self.track_inside = bool(spheres == "ellipsoids" and transparent.any())
        # The integrator recomputes the hit point and normal of an `ellipsoids` hit from the
        # sphere (core/SHADING.md section 2, robust): Mitsuba solves the quadratic in the unit
        # sphere's frame, where a small sphere far from the origin loses most of its digits.
        self.refine_spheres = bool(together.any())
        if self.refine_spheres:
            self.sphere_center = mi.Point3f(sc.sphere_center[together].astype(np.float32).T)
            self.sphere_radius = mi.Float(sc.sphere_radius[together].astype(np.float32))
        _, radius = sc.bounds()
        half = 1e4 * radius
        for i, (n, off, m) in enumerate(sc.planes):
            M = np.eye(4)
            M[:3, :3] = _frame_to(n) * half
            M[:3, 3] = n * off
            d[f"plane{i}"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f(M.tolist())}
            owner[f"plane{i}"] = m
        self.scene = mi.load_dict(d)
        # Shape registry id -> material (reinterpreting a ShapePtr gives its id).
        ids = {}
        for s in self.scene.shapes():
            ids[s.id()] = int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(s))[0])
        table = np.full(max(ids.values(), default=0) + 1, PER_PRIM, dtype=np.uint32)
        for key, m in owner.items():
            table[ids[key]] = m
        self.shape_material = mi.UInt32(table)
        # Shape id -> plane index: the integrator puts plane hits back on the plane (the hit
        # point Mitsuba interpolates over a rectangle 1e4 x the scene wide is off by ~ulp(1e4 r)).
        ptable = np.full(len(table), NONE, dtype=np.uint32)
        for i in range(len(sc.planes)):
            ptable[ids[f"plane{i}"]] = i
        self.shape_plane = mi.UInt32(ptable)
        # Shape id -> its first triangle in tri_abs (the bound offset of triangle hits).
        ttable = np.full(len(table), NONE, dtype=np.uint32)
        for key, base in tri_base.items():
            ttable[ids[key]] = base
        self.shape_triangle = mi.UInt32(ttable)
        self.has_triangles = bool(tri_abs)
        if self.has_triangles:
            self.tri_abs = mi.Vector3f(np.concatenate(tri_abs).T)
        self.has_planes = bool(sc.planes)
        if self.has_planes:
            self.plane_normal = mi.Vector3f(np.array([n for n, _, _ in sc.planes],
                                                     dtype=np.float32).T)
            self.plane_offset = mi.Float(np.array([o for _, o, _ in sc.planes], dtype=np.float32))
        self.sphere_material = mi.UInt32(sc.sphere_material[together] if together.any()
                                         else np.zeros(1, np.uint32))
        mats = sc.materials or [{"ambient": [0] * 3, "diffuse": [0] * 3, "specular": [0] * 3,
                                 "exponent": 1.0, "reflectance": 0.0, "opacity": 1.0, "ior": 1.0}]
        col = lambda k: mi.Color3f(np.array([m[k] for m in mats], dtype=np.float32).T)
        flt = lambda k: mi.Float(np.array([m[k] for m in mats], dtype=np.float32))
        self.ambient, self.diffuse, self.specular = col("ambient"), col("diffuse"), col("specular")
        self.exponent, self.reflectance = flt("exponent"), flt("reflectance")
        self.opacity, self.ior = flt("opacity"), flt("ior")
        # Procedural materials: slot 0 is no pattern; material i with one gets its own callable
        # for dr.switch (a symbolic call in the megakernel, one launch per pattern evaluated).
        self.pattern_targets = [_plain_target]
        slots = np.zeros(max(len(mats), 1), dtype=np.uint32)
        for i, m in enumerate(sc.materials):
            if m.get("pattern", "none") != "none":
                slots[i] = len(self.pattern_targets)
                self.pattern_targets.append(_pattern_target(m, self.scale))
        self.pattern_slot = mi.UInt32(slots)
        self.has_patterns = len(self.pattern_targets) > 1
        # Cubemap (section 9): the six faces as linear floats, read as rtlab's readImage does
        # (8-bit images are sRGB-decoded in double, float images taken as they are).
        self.cubemap_size = 0
        if sc.cubemap:
            faces = [_read_linear(f) for f in sc.cubemap]
            n = faces[0].shape[0]
            if any(f.shape[:2] != (n, n) for f in faces):
                raise NotConverted(f"{sc.path}: /environment/cubemap: faces must be square and of "
                                   f"one size")
            self.cubemap_size = n
            self.cubemap = mi.Float(np.concatenate([f.ravel() for f in faces]))
        self.convert_s = time.perf_counter() - t0
        spheres_said = "none"
        if ns:
            spheres_said = (f"{int(together.sum())} in one ellipsoids shape, "
                            f"{self.sphere_shapes} sphere shapes")
            if self.track_inside:
                spheres_said += ", the sphere a ray is inside tested analytically"
        self.representation = {
            "spheres": spheres_said,
            "planes": f"rectangle half-size {half:g}",
            "meshes": f"{len(sc.triangles)} merged per material",
            "patterns": len(self.pattern_targets) - 1,
            "scale": self.scale,
        }


def _read_linear(path):
    """An image as linear RGB float32 (H, W, 3), as rtlab's image/image_io.cpp readImage: 8- and
    16-bit images sRGB-decoded (in double), float images as stored; gray replicated."""
    bmp = mi.Bitmap(path)
    a = np.array(bmp)
    if a.ndim == 2:
        a = a[..., None]
    a = np.repeat(a[..., :1], 3, axis=2) if a.shape[2] < 3 else a[..., :3]
    if np.issubdtype(a.dtype, np.integer):
        s = a.astype(np.float64) / np.iinfo(a.dtype).max
        a = np.where(s <= 0.04045, s / 12.92, np.power((s + 0.055) / 1.055, 2.4))
    return a.astype(np.float32)


# ---- the integrator --------------------------------------------------------------------------

def _hash(v):
    """core/sampling.h Sampling_Hash (PCG, Jarzynski and Olano 2020) on UInt32 lanes."""
    state = v * 747796405 + 2891336453
    word = ((state >> ((state >> 28) + 4)) ^ state) * 277803737
    return (word >> 22) ^ word


def _hash_const(v):
    v = np.uint32(v)
    with np.errstate(over="ignore"):
        state = v * np.uint32(747796405) + np.uint32(2891336453)
        word = ((state >> ((state >> np.uint32(28)) + np.uint32(4))) ^ state) * np.uint32(277803737)
    return int((word >> np.uint32(22)) ^ word)


def _unit(key, j, k, dim):
    """Sampling_Unit: a number in [0, 1) for dimension dim of shadow sample k toward light j."""
    h = _hash(key ^ _hash_const((j * 256 + k) * 2 + dim))
    return mi.Float(h >> 8) * (1.0 / 16777216.0)


def _sky(sc, d):
    z, h, g = (mi.Color3f(*[float(c) for c in sc.sky[k]]) for k in ("zenith", "horizon", "ground"))
    y = d.y
    return dr.select(y >= 0, h + (z - h) * y, h + (g - h) * (-y))


def _cubemap(cv, d, active):
    """core/cl/shade.cl Cubemap_Lookup: the major axis picks the face (ties: x, then y), then
    bilinear between texel centres, clamped to the face's edge."""
    a = dr.abs(d)
    on_x = (a.x >= a.y) & (a.x >= a.z)
    on_y = ~on_x & (a.y >= a.z)
    face = dr.select(on_x, dr.select(d.x >= 0, 0, 1),
                     dr.select(on_y, dr.select(d.y >= 0, 2, 3), dr.select(d.z >= 0, 4, 5)))
    s_ = dr.select(on_x, dr.select(d.x >= 0, -d.z, d.z),
                   dr.select(on_y, d.x, dr.select(d.z >= 0, d.x, -d.x)))
    t_ = dr.select(on_x, -d.y, dr.select(on_y, dr.select(d.y >= 0, d.z, -d.z), -d.y))
    ma = dr.select(on_x, a.x, dr.select(on_y, a.y, a.z))
    n = cv.cubemap_size
    fx = (s_ / ma + 1.0) * 0.5 * n - 0.5
    fy = (t_ / ma + 1.0) * 0.5 * n - 0.5
    x0, y0 = dr.floor(fx), dr.floor(fy)
    tx, ty = fx - x0, fy - y0
    ix, iy = mi.Int32(x0), mi.Int32(y0)
    face = mi.Int32(face)

    def texel(x, y):
        x = dr.select(x < 0, 0, dr.select(x > n - 1, n - 1, x))
        y = dr.select(y < 0, 0, dr.select(y > n - 1, n - 1, y))
        i = mi.UInt32(((face * n + y) * n + x) * 3)
        return mi.Color3f(dr.gather(mi.Float, cv.cubemap, i, active),
                          dr.gather(mi.Float, cv.cubemap, i + 1, active),
                          dr.gather(mi.Float, cv.cubemap, i + 2, active))

    top = texel(ix, iy) * (1.0 - tx) + texel(ix + 1, iy) * tx
    bot = texel(ix, iy + 1) * (1.0 - tx) + texel(ix + 1, iy + 1) * tx
    return top * (1.0 - ty) + bot * ty


def _max0(x):
    """max(x, 0) as a select: LLVM 15 (Debian's libllvm15, which Dr.Jit's LLVM backend loads)
    cannot compile the llvm.maximum intrinsic that dr.maximum emits on x86 ("Cannot select
    fmaximum"); NaN gives 0 here as OpenCL's fmax(x, 0) does."""
    return dr.select(x > 0, x, 0.0)


U = 2.0 ** -24


def _gamma(n):
    return n * U / (1 - n * U)


def _next_float(x, up):
    """nextafter(x, +inf) where `up`, else nextafter(x, -inf), on the float's bits."""
    bits = dr.reinterpret_array(mi.UInt32, x)
    grow = (x > 0) == up  # the magnitude grows
    bits = dr.select(grow, bits + 1, bits - 1)
    bits = dr.select(x == 0, dr.select(up, mi.UInt32(1), mi.UInt32(0x80000001)), bits)
    return dr.reinterpret_array(mi.Float, bits)


def _spawn(p, ng, err, side):
    """core/cl/shade.cl Shade_SpawnOrigin (SHADING.md section 3, bound): from p, whose
    components are off by at most err, along side * ng by dot(|ng|, err), then each component one
    float further, so that the addition cannot round the offset away."""
    w = side * ng
    o = p + dr.dot(dr.abs(ng), err) * w
    return mi.Point3f(*[dr.select(wc != 0, _next_float(oc, wc > 0), oc)
                        for oc, wc in zip((o.x, o.y, o.z), (w.x, w.y, w.z))])


def _fresnel(cos_i, n1, n2):
    sin_t = n1 / n2 * dr.sqrt(_max0(1.0 - cos_i * cos_i))
    cos_t = dr.sqrt(_max0(1.0 - sin_t * sin_t))
    rs = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    rp = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    return dr.select(sin_t >= 1.0, 1.0, (rs * rs + rp * rp) / 2.0)


# ---- procedural materials (core/SHADING.md section 5, core/cl/procedural.cl) -----------------

def _phash(x, y, z):
    """Procedural_Hash of lattice point (x, y, z) (Int32 lanes)."""
    h = (mi.UInt32(x) * 0x8da6b343) ^ (mi.UInt32(y) * 0xd8163841) ^ (mi.UInt32(z) * 0xcb1ab31f)
    h ^= h >> 16
    h *= 0x7feb352d
    h ^= h >> 15
    h *= 0x846ca68b
    h ^= h >> 16
    return h


def _grad(h, x, y, z):
    h = h & 15
    u = dr.select(h < 8, x, y)
    v = dr.select(h < 4, y, dr.select((h == 12) | (h == 14), x, z))
    return dr.select((h & 1) != 0, -u, u) + dr.select((h & 2) != 0, -v, v)


def _fade(t):
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def _noise(p):
    f = dr.floor(p)
    x, y, z = mi.Int32(f.x), mi.Int32(f.y), mi.Int32(f.z)
    dx, dy, dz = p.x - f.x, p.y - f.y, p.z - f.z
    u, v, w = _fade(dx), _fade(dy), _fade(dz)
    n000 = _grad(_phash(x, y, z), dx, dy, dz)
    n100 = _grad(_phash(x + 1, y, z), dx - 1.0, dy, dz)
    n010 = _grad(_phash(x, y + 1, z), dx, dy - 1.0, dz)
    n110 = _grad(_phash(x + 1, y + 1, z), dx - 1.0, dy - 1.0, dz)
    n001 = _grad(_phash(x, y, z + 1), dx, dy, dz - 1.0)
    n101 = _grad(_phash(x + 1, y, z + 1), dx - 1.0, dy, dz - 1.0)
    n011 = _grad(_phash(x, y + 1, z + 1), dx, dy - 1.0, dz - 1.0)
    n111 = _grad(_phash(x + 1, y + 1, z + 1), dx - 1.0, dy - 1.0, dz - 1.0)
    x00, x10 = n000 + u * (n100 - n000), n010 + u * (n110 - n010)
    x01, x11 = n001 + u * (n101 - n001), n011 + u * (n111 - n011)
    y0, y1 = x00 + v * (x10 - x00), x01 + v * (x11 - x01)
    return y0 + w * (y1 - y0)


def _fbm(p, octaves, turbulence):
    """Procedural_Fbm, its octave loop unrolled (octaves is the material's constant)."""
    total, amp = mi.Float(0.0), 1.0
    for _ in range(octaves):
        n = _noise(p)
        total += amp * (dr.abs(n) if turbulence else n)
        p = p * 2.0
        p = p - 65536.0 * dr.round(p / 65536.0)
        amp *= 0.5
    return total


def _pattern_target(m, world_scale):
    """The dr.switch target of a procedural material: (p, N, diffuse) -> (diffuse', N'), every
    parameter a constant of the callable, as rtlab's pattern kernels bake the pattern in."""
    kind, octaves, bump = m["pattern"], int(m["octaves"]), float(m["bump"])
    scale = float(np.float32(m["scale"])) / world_scale  # the peer renders the scene scaled
    d2 = [float(c) for c in m["diffuse2"]]

    def target(p, n, diffuse):
        q = mi.Vector3f(p) * scale
        if kind == "bump":
            h = 0.015625
            f0 = _fbm(q, octaves, False)
            g = mi.Vector3f(_fbm(q + mi.Vector3f(h, 0, 0), octaves, False) - f0,
                            _fbm(q + mi.Vector3f(0, h, 0), octaves, False) - f0,
                            _fbm(q + mi.Vector3f(0, 0, h), octaves, False) - f0) / h
            g = g - dr.dot(g, n) * n
            return diffuse, dr.normalize(n - bump * g)
        if kind == "checker":
            f = dr.floor(q)
            t = dr.select(((mi.Int32(f.x) + mi.Int32(f.y) + mi.Int32(f.z)) & 1) != 0, 1.0, 0.0)
        elif kind == "marble":
            t = 0.5 + 0.5 * dr.sin(q.x + 5.0 * _fbm(q, octaves, True))
        elif kind == "wood":
            r = dr.sqrt(q.x * q.x + q.z * q.z) + 0.5 * _fbm(q, octaves, False)
            t = 0.5 + 0.5 * dr.sin(6.2831853 * r)
        else:  # granite
            t = 0.5 + 1.5 * _fbm(q, octaves, False)
            t = dr.select(t < 0.0, 0.0, dr.select(t > 1.0, 1.0, t))  # clamp (see _max0)
        return diffuse + t * (mi.Color3f(*d2) - diffuse), n

    return target


def _plain_target(p, n, diffuse):
    return diffuse, n


def _entry_type():
    """A pending child of the ray tree (a stack entry): a dataclass PyTree of the variant's
    types."""
    global Entry

    @dataclasses.dataclass
    class Entry:
        o: mi.Point3f
        d: mi.Vector3f
        w: mi.Color3f
        depth: mi.UInt32
        inside: mi.UInt32  # the sphere the ray starts inside, or NONE

    return Entry


Entry = None


STACKS = ("local", "registers")


def _select_entry(mask, a, b):
    return Entry(*[dr.select(mask, getattr(a, f.name), getattr(b, f.name))
                   for f in dataclasses.fields(Entry)])


class _RegisterStack:
    """The per-lane stack as B loop variables (a list of Entry PyTrees), written and read
    through selects: no local memory, O(B) selects per push and pop. The fallback where
    dr.alloc_local is unavailable, and a comparison of the two (--stack registers)."""

    def __init__(self, slots):
        self.slots = list(slots)

    def write(self, value, index, active):
        for i in range(len(self.slots)):
            self.slots[i] = _select_entry(active & (index == i), value, self.slots[i])

    def read(self, index, active):
        out = self.slots[0]
        for i in range(1, len(self.slots)):
            out = _select_entry(index == i, self.slots[i], out)
        return out


def render(cv, width, height, bounces, shadow_samples=None, shadow_strength=None,
           count_rays=False, stack="local"):
    """The frame as Dr.Jit arrays (Color3f of width*height lanes, row 0 on top) and, with
    count_rays, the rays cast: [traced (primary and secondary), shadow], UInt64 arrays of 1.
    Nothing is evaluated here: the caller's dr.eval launches the kernel(s)."""
    sc = cv.sc
    S = int(shadow_samples if shadow_samples is not None else sc.render["shadow_samples"])
    strength = float(shadow_strength if shadow_strength is not None
                     else sc.render["shadow_strength"])
    B = int(bounces)
    scene = cv.scene
    W, H = int(width), int(height)

    # Section 1: primary rays, in float as core/cl/camera.cl computes them.
    idx = dr.arange(mi.UInt32, W * H)
    py = idx // W
    px = idx - py * W
    Wf, Hf = np.float32(W), np.float32(H)
    D = float(np.float32(1.0) / np.float32(math.tan(np.float32(sc.fov) * np.float32(0.5))))
    ncx = (2.0 * (mi.Float(px) + 0.5) / float(Wf) - 1.0) * float(Wf / Hf)
    ncy = 1.0 - 2.0 * (mi.Float(py) + 0.5) / float(Hf)
    ca, sa = float(np.cos(np.float32(sc.pitch))), float(np.sin(np.float32(sc.pitch)))
    cb, sb = float(np.cos(np.float32(sc.yaw))), float(np.sin(np.float32(sc.yaw)))
    ox, oy, oz = ncx, ncy * ca + D * sa, D * ca - ncy * sa
    d = dr.normalize(mi.Vector3f(ox * cb + oz * sb, oy, oz * cb - ox * sb))
    o = mi.Point3f(*[float(c) for c in sc.position])
    o = dr.zeros(mi.Point3f, W * H) + o

    lights = [(mi.Point3f(*map(float, p)), mi.Color3f(*map(float, c)), float(r))
              for p, c, r in sc.lights]
    key_xy = [px, py]

    w = dr.full(mi.Color3f, 1.0, W * H)
    depth = dr.zeros(mi.UInt32, W * H)
    inside_sphere = dr.full(mi.UInt32, NONE, W * H)
    sp = dr.zeros(mi.UInt32, W * H)
    L = dr.zeros(mi.Color3f, W * H)
    nrays = dr.zeros(mi.UInt32, W * H)   # rays traced (primary and secondary)
    nshadow = dr.zeros(mi.UInt32, W * H)  # shadow rays
    active = dr.full(mi.Bool, True, W * H)
    if stack not in STACKS:
        raise ValueError(f"stack must be one of {', '.join(STACKS)}, got {stack}")
    local = stack == "local"
    entry = _entry_type()
    stack = (dr.alloc_local(entry, max(B, 1)) if local
             else [dr.zeros(entry, W * H) for _ in range(max(B, 1))])
    track = cv.track_inside

    def on_sphere(o, d, k, mask, far):
        """Ray (o, unit d) against sphere k, as core/SHADING.md section 2's robust test: the
        far (or near) root t, inf where it misses or lies behind, and the point put back on the
        sphere with its outward normal."""
        c = dr.gather(mi.Point3f, cv.sphere_center, k, mask)
        r = dr.gather(mi.Float, cv.sphere_radius, k, mask)
        oc = o - c
        bp = -dr.dot(oc, d)
        f = oc + bp * d
        disc = r * r - dr.dot(f, f)
        q = bp + dr.mulsign(dr.sqrt(_max0(disc)), bp)
        t0 = (dr.dot(oc, oc) - r * r) / q
        t = dr.select(far == (t0 > q), t0, q)  # far: the larger root; near: the smaller
        f = f - dr.dot(f, d) * d
        h = dr.sqrt(_max0(r * r - dr.dot(f, f)))
        n = dr.normalize(dr.select(far, f + h * d, f - h * d))
        return dr.select(mask & (disc >= 0) & (t > 0), t, dr.inf), c + r * n, n

    def body(o, d, w, depth, inside_sphere, sp, L, nrays, nshadow, active, stack):
        st = stack if local else _RegisterStack(stack)
        ray = mi.Ray3f(o, d)
        si = scene.ray_intersect(ray, mi.RayFlags.Minimal | mi.RayFlags.ShadingFrame, False,
                                 active)
        if count_rays:
            nrays += dr.select(active, 1, 0)
        sid = dr.reinterpret_array(mi.UInt32, si.shape)
        m = dr.gather(mi.UInt32, cv.shape_material, sid, active & si.is_valid())
        if cv.has_planes:  # a plane hit: o + t d, projected onto the plane (SHADING.md 2, bound)
            pl = dr.gather(mi.UInt32, cv.shape_plane, sid, active & si.is_valid())
            on_plane = active & si.is_valid() & (pl != NONE)
            pn = dr.gather(mi.Vector3f, cv.plane_normal, pl, on_plane)
            po = dr.gather(mi.Float, cv.plane_offset, pl, on_plane)
            pp = o + si.t * d
            si.p = dr.select(on_plane, pp + (po - dr.dot(pn, pp)) * pn, si.p)
        per_prim = active & si.is_valid() & (m == PER_PRIM)
        m = dr.select(per_prim, dr.gather(mi.UInt32, cv.sphere_material, si.prim_index, per_prim),
                      m)
        hit_sphere = dr.select(per_prim, si.prim_index, NONE)
        if cv.refine_spheres:  # the front hit `ellipsoids` reported, recomputed
            _, pf, nf = on_sphere(o, d, si.prim_index, per_prim, False)
            si.p = dr.select(per_prim, pf, si.p)
            si.n = dr.select(per_prim, nf, si.n)
            si.sh_frame.n = dr.select(per_prim, nf, si.sh_frame.n)
        if track:  # the exit from the sphere the ray is inside, which `ellipsoids` never reports
            in_mask = active & (inside_sphere != NONE)
            te, pe, ne = on_sphere(o, d, inside_sphere, in_mask, True)
            use = in_mask & (te < si.t)
            si.t = dr.select(use, te, si.t)
            si.p = dr.select(use, pe, si.p)
            si.n = dr.select(use, ne, si.n)
            si.sh_frame.n = dr.select(use, ne, si.sh_frame.n)
            m = dr.select(use, dr.gather(mi.UInt32, cv.sphere_material, inside_sphere, use), m)
            hit_sphere = dr.select(use, inside_sphere, hit_sphere)
        hit = active & si.is_valid()
        miss = active & ~si.is_valid()
        env = _cubemap(cv, d, miss) if cv.cubemap_size else _sky(sc, d)
        L += dr.select(miss, w * env, 0.0)

        amb = dr.gather(mi.Color3f, cv.ambient, m, hit)
        dif = dr.gather(mi.Color3f, cv.diffuse, m, hit)
        spc = dr.gather(mi.Color3f, cv.specular, m, hit)
        expo = dr.gather(mi.Float, cv.exponent, m, hit)
        refl = dr.gather(mi.Float, cv.reflectance, m, hit)
        opac = dr.gather(mi.Float, cv.opacity, m, hit)
        ior = dr.gather(mi.Float, cv.ior, m, hit)

        inside = dr.dot(si.n, d) > 0
        N = mi.Vector3f(dr.select(inside, -si.sh_frame.n, si.sh_frame.n))
        Ng = mi.Vector3f(dr.select(inside, -si.n, si.n))
        p = mi.Point3f(si.p)
        # The bound on p's rounding error (SHADING.md section 3): spheres gamma(5)(|c| + r|N|),
        # planes gamma(6)(|p| + |offset|), triangles gamma(7)(|v0| + |v1| + |v2|); anything else
        # (Mitsuba's own sphere shapes, --spheres hybrid or shapes) gamma(7)(|p.x|+|p.y|+|p.z|)
        # along the normal, as rtlab's Shade_Offset.
        ap = dr.abs(p)
        l1 = dr.abs(Ng.x) + dr.abs(Ng.y) + dr.abs(Ng.z)
        err = dr.full(mi.Vector3f, _gamma(7), W * H) * (ap.x + ap.y + ap.z) \
            / dr.select(l1 > 0, l1, 1.0)
        if cv.has_triangles:
            tb = dr.gather(mi.UInt32, cv.shape_triangle, sid, hit)
            on_tri = hit & (tb != NONE)
            err = dr.select(on_tri, _gamma(7) * dr.gather(mi.Vector3f, cv.tri_abs,
                                                           tb + si.prim_index, on_tri), err)
        if cv.has_planes:
            err = dr.select(on_plane, _gamma(6) * (ap + dr.abs(po)), err)
        if cv.refine_spheres:
            on_sph = hit & (hit_sphere != NONE)
            sc_ = dr.gather(mi.Point3f, cv.sphere_center, hit_sphere, on_sph)
            sr_ = dr.gather(mi.Float, cv.sphere_radius, hit_sphere, on_sph)
            err = dr.select(on_sph, _gamma(5) * (dr.abs(sc_) + sr_ * dr.abs(N)), err)
        o_out = _spawn(p, Ng, err, 1.0)  # reflection and shadow rays

        def occluded_by(q, lit):
            """Whether the shadow ray from o_out toward q is blocked before q (0 < t < |q - o|):
            Mitsuba's ray_test, and the sphere its origin is inside."""
            v = q - o_out
            length = dr.norm(v)
            dir_ = v / length
            blocked = scene.ray_test(mi.Ray3f(o_out, dir_, length, 0.0, mi.Color0f()), lit)
            if track:
                in_mask = lit & (inside_sphere != NONE)
                te, _, _ = on_sphere(o_out, dir_, inside_sphere, in_mask, True)
                blocked |= in_mask & (te < length)
            return blocked

        # Section 5, procedural materials: D' or a bumped shading normal for the sum below;
        # shadow rays and children keep N.
        Ns = N
        if cv.has_patterns:
            slot = dr.gather(mi.UInt32, cv.pattern_slot, m, hit)
            dif, Ns = dr.switch(dr.select(hit, slot, 0), cv.pattern_targets, p, N, dif)
            Ns = mi.Vector3f(Ns)

        # Section 4 and 5: shadows and Blinn-Phong.
        base = mi.Color3f(amb)
        key = _hash(_hash(_hash(_hash(depth) ^ 0) ^ key_xy[1]) ^ key_xy[0])
        for j, (lp, lc, lr) in enumerate(lights):
            l = dr.normalize(lp - p)
            lit = hit & (dr.dot(N, l) > 0)  # shadow rays only toward lights N faces
            ndl = dr.dot(Ns, l)
            occluded = mi.Float(0.0)
            if lr == 0.0:
                occluded = dr.select(occluded_by(lp, lit), 1.0, 0.0)
                if count_rays:
                    nshadow += dr.select(lit, 1, 0)
            else:
                sign = dr.select(l.z >= 0, 1.0, -1.0)
                a = -1.0 / (sign + l.z)
                b = l.x * l.y * a
                tt = mi.Vector3f(1.0 + sign * l.x * l.x * a, sign * b, -sign * l.x)
                bt = mi.Vector3f(b, sign + l.y * l.y * a, -l.y)
                turn = _unit(key, j, 0, 0)
                for k in range(S):
                    area = (k + _unit(key, j, k, 1)) / S
                    rho = lr * dr.sqrt(area)
                    phi = GOLDEN * k + TWO_PI * turn
                    q = lp + rho * (dr.cos(phi) * tt + dr.sin(phi) * bt)
                    occluded += dr.select(occluded_by(q, lit), 1.0, 0.0)
                if count_rays:
                    nshadow += dr.select(lit, S, 0)
                occluded = occluded / S
            vis = 1.0 - strength * occluded
            h = dr.normalize(l - d)
            ndh = _max0(dr.dot(Ns, h))
            spec = dr.select(expo == 0, 1.0, dr.power(ndh, expo))
            base += dr.select(hit & (ndl > 0), vis * lc * (dif * ndl + spc * spec), 0.0)

        # Sections 6 to 8: children and their weights.
        transparent = opac < 1.0
        branch = hit & (depth < B)
        has_refl = branch & ((refl > 0) | transparent)
        eta = dr.select(inside, ior, 1.0 / ior)  # n1 / n2
        c = -dr.dot(N, d)
        s2 = eta * eta * (1.0 - c * c)
        has_refr = branch & transparent & (s2 <= 1.0)
        rdir = dr.normalize(d - 2.0 * N * dr.dot(d, N))
        tdir = dr.normalize(eta * d + (eta * c - dr.sqrt(_max0(1.0 - s2))) * N)
        n1 = dr.select(inside, ior, 1.0)
        n2 = dr.select(inside, 1.0, ior)
        F = dr.select(transparent, _fresnel(c, n1, n2), refl)
        F = dr.select(has_refl, F, 0.0)
        op = dr.select(has_refr, opac, 1.0)
        L += dr.select(hit, w * ((1.0 - F) * op) * base, 0.0)
        o_refl = o_out
        o_refr = _spawn(p, Ng, err, -1.0)
        w_refl = w * F
        w_refr = w * ((1.0 - F) * (1.0 - op))
        # The sphere each child starts inside: reflections stay where the ray was; a refraction
        # leaves the sphere it hit from inside, or enters the sphere it hit from outside.
        in_refl = inside_sphere
        in_refr = inside_sphere
        if track:
            in_refr = dr.select(inside & (hit_sphere == inside_sphere), NONE,
                                dr.select(~inside & (hit_sphere != NONE), hit_sphere,
                                          inside_sphere))

        both = has_refl & has_refr
        st.write(Entry(o_refr, tdir, w_refr, depth + 1, in_refr), sp, both)
        sp = dr.select(both, sp + 1, sp)
        go = has_refl | has_refr
        pop = active & ~go & (sp > 0)
        e = st.read(sp - 1, pop)
        sp = dr.select(pop, sp - 1, sp)
        o = dr.select(has_refl, o_refl, dr.select(has_refr, o_refr, e.o))
        d = dr.select(has_refl, rdir, dr.select(has_refr, tdir, e.d))
        w = dr.select(has_refl, w_refl, dr.select(has_refr, w_refr, e.w))
        depth = dr.select(go, depth + 1, e.depth)
        inside_sphere = dr.select(has_refl, in_refl, dr.select(has_refr, in_refr, e.inside))
        active = go | pop
        return (o, d, w, depth, inside_sphere, sp, L, nrays, nshadow, active,
                stack if local else st.slots)

    names = ("o", "d", "w", "depth", "inside_sphere", "sp", "L", "nrays", "nshadow", "active",
             "stack")
    state = dr.while_loop(
        state=(o, d, w, depth, inside_sphere, sp, L, nrays, nshadow, active, stack),
        cond=lambda *st: st[9],
        body=body,
        labels=names,
        label="rtlab_whitted")
    L, nrays, nshadow = state[6], state[7], state[8]
    if not count_rays:
        return L, None
    return L, [dr.sum(mi.UInt64(nrays)), dr.sum(mi.UInt64(nshadow))]


def to_numpy(L, width, height):
    return np.stack([np.asarray(L.x), np.asarray(L.y), np.asarray(L.z)], axis=-1) \
        .reshape(height, width, 3).astype(np.float32)


def write_image(img, path, half=False):
    """.npy, .exr (32-bit float, or 16-bit with half) or .png (clamped, sRGB, 8-bit)."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npy":
        np.save(path, img)
    elif ext == ".exr":
        mi.Bitmap(img.astype(np.float16) if half else img).write(path)
    elif ext == ".png":
        c = np.clip(img, 0, 1)
        srgb = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
        mi.Bitmap((srgb * 255 + 0.5).astype(np.uint8), pixel_format=mi.Bitmap.PixelFormat.RGB) \
            .write(path)
    else:
        raise SystemExit(f"{path}: output must be .exr, .png or .npy")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--size", help="WxH [scene default]")
    ap.add_argument("--bounces", type=int, help="bounce limit B [scene default]")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--mode", default="symbolic", choices=MODES)
    ap.add_argument("--spheres", default="ellipsoids", choices=SPHERES)
    ap.add_argument("--stack", default="local", choices=STACKS,
                    help="the per-lane stack: local memory or loop variables [local]")
    ap.add_argument("-o", "--output", default="peer.exr")
    ap.add_argument("--stats", action="store_true", help="print rays and kernel times")
    a = ap.parse_args(argv)
    try:
        sc = Scene(a.scene)
        w = h = None
        if a.size:
            w, h = (int(v) for v in a.size.lower().split("x"))
        st = sc.settings(w, h, a.bounces)
    except NotConverted as e:
        print(f"whitted.py: not converted: {e}", file=sys.stderr)
        return 2
    setup(a.variant)
    set_mode(a.mode)
    cv = Converted(sc, a.spheres)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    L, rays = render(cv, st["width"], st["height"], st["bounces"], count_rays=a.stats,
                     stack=a.stack)
    dr.eval(L, rays)
    dr.sync_thread()
    hist = dr.kernel_history()
    img = to_numpy(L, st["width"], st["height"])
    write_image(img, a.output)
    if a.stats:
        ms = sum(k.get("execution_time", 0.0) for k in hist)
        print(f"{sc.name}: {st['width']}x{st['height']} B={st['bounces']} {a.variant} {a.mode}: "
              f"{len(hist)} kernels, {ms:.2f} ms (with compile), rays traced {int(rays[0][0])}, "
              f"shadow {int(rays[1][0])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
