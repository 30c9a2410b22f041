"""rtlab's scene files (scenes/README.md, core/scene_loader.cpp) read into numpy arrays for the
Mitsuba 3 peer (peers/mitsuba/whitted.py): camera, materials, spheres, planes, loose triangles and
OBJ meshes with their transforms, lights, sky and render defaults.

Only what the peer renders the same way as rtlab is accepted. Everything else raises
NotConverted with one line naming the feature and where it is (glTF/PLY models, bare models,
anti-aliasing, adaptive AA): the peer refuses rather than guesses.
The loader's own validation (ranges, unknown keys) is rtlab's job; this reader assumes a scene
that `rtlab render` accepts.

Standard library and numpy only (no Mitsuba), so that it can be tested anywhere.
"""
import json
import math
import os
import re

import numpy as np


class NotConverted(Exception):
    """A scene feature the peer does not convert; the message is one line."""


SKY = {"zenith": [0.35, 0.55, 0.95], "horizon": [0.85, 0.9, 1.0], "ground": [0.3, 0.27, 0.25]}
MATERIAL_DEFAULTS = {"ambient": [0, 0, 0], "diffuse": [0.8, 0.8, 0.8], "specular": [0, 0, 0],
                     "exponent": 32.0, "reflectance": 0.0, "opacity": 1.0, "ior": 1.0,
                     "pattern": "none", "octaves": 4, "scale": 1.0, "diffuse2": [0.1, 0.1, 0.1],
                     "bump": 0.5}
PATTERNS = ("none", "checker", "marble", "wood", "granite", "bump")
RENDER_DEFAULTS = {"width": 320, "height": 240, "bounces": 3, "shadow_samples": 1, "aa": 1,
                   "shadow_strength": 1.0, "adaptive_aa": False}
DEG = math.pi / 180.0


def _strip_comments(text):
    """JSON with // and /* */ comments (the loader allows them), outside strings."""
    out, i, n, in_str = [], 0, len(text), False
    while i < n:
        c = text[i]
        if in_str:
            out.append(c)
            if c == "\\" and i + 1 < n:
                out.append(text[i + 1])
                i += 1
            elif c == '"':
                in_str = False
        elif c == '"':
            in_str = True
            out.append(c)
        elif text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            i = n if j < 0 else j + 2
            continue
        else:
            out.append(c)
        i += 1
    return "".join(out)


def read_obj(path):
    """Triangles of an OBJ file as rtlab's loader reads them: (positions (T,3,3), normals (T,3,3))
    float64. Polygons are fanned (rtlab uses tinyobjloader's ear clipping: the same for convex
    faces). The file's normals are used when every corner has one, else area-weighted smooth
    normals per position; zero-area triangles are dropped."""
    vs, vns, faces = [], [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vs.append([float(x) for x in parts[1:4]])
            elif parts[0] == "vn":
                vns.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                corners = []
                for c in parts[1:]:
                    fields = c.split("/")
                    vi = int(fields[0])
                    vi = vi - 1 if vi > 0 else len(vs) + vi
                    ni = None
                    if len(fields) >= 3 and fields[2]:
                        ni = int(fields[2])
                        ni = ni - 1 if ni > 0 else len(vns) + ni
                    corners.append((vi, ni))
                for k in range(1, len(corners) - 1):
                    faces.append((corners[0], corners[k], corners[k + 1]))
    if not faces:
        raise NotConverted(f"{path}: no triangles")
    V = np.asarray(vs, dtype=np.float64)
    vi = np.array([[c[0] for c in f] for f in faces], dtype=np.int64)
    P = V[vi]
    area2 = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    keep = np.linalg.norm(area2, axis=1) > 0
    have_normals = all(c[1] is not None for f in faces for c in f)
    if have_normals:
        N = np.asarray(vns, dtype=np.float64)[np.array([[c[1] for c in f] for f in faces])]
    else:  # area-weighted smooth normals per position (the cross product is 2 x area x n)
        acc = np.zeros_like(V)
        for k in range(3):
            np.add.at(acc, vi[keep, k], area2[keep])
        N = acc[vi]
    N = N / np.maximum(np.linalg.norm(N, axis=2, keepdims=True), 1e-30)
    return P[keep], N[keep]


def _rotation(deg):
    ax, ay, az = (d * DEG for d in deg)
    cx, sx, cy, sy, cz, sz = math.cos(ax), math.sin(ax), math.cos(ay), math.sin(ay), \
        math.cos(az), math.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


class Scene:
    """The scene as arrays. Materials are indexed in file order (as rtlab stores them)."""

    def __init__(self, path):
        self.path = path
        self.name = os.path.splitext(os.path.basename(path))[0]
        ext = os.path.splitext(path)[1].lower()
        if ext != ".json":
            raise NotConverted(f"{path}: bare models ({ext}) are not converted; wrap the model in "
                               f"a scene file with 'meshes'")
        with open(path) as f:
            j = json.loads(_strip_comments(f.read()))
        self.dir = os.path.dirname(path)
        self._camera(j["camera"])
        self._materials(j.get("materials", {}))
        self._objects(j)
        self._lights(j.get("lights", []))
        env = j.get("environment", {"sky": {}})
        self.cubemap = None  # six face paths (+x, -x, +y, -y, +z, -z); the peer reads them
        if "cubemap" in env:
            self.cubemap = [os.path.join(self.dir, f) for f in env["cubemap"]]
            env = {"sky": {}}
        self.sky = {k: np.array(env["sky"].get(k, v), dtype=np.float32) for k, v in SKY.items()}
        self.render = dict(RENDER_DEFAULTS, **j.get("render", {}))
        self.render.pop("accel", None)

    def _camera(self, c):
        self.position = np.array(c["position"], dtype=np.float32)
        if "look_at" in c:
            d = np.array(c["look_at"], dtype=np.float64) - self.position.astype(np.float64)
            d /= np.linalg.norm(d)
            self.pitch = float(np.float32(math.asin(max(-1.0, min(1.0, d[1])))))
            self.yaw = float(np.float32(math.atan2(d[0], d[2])))
        else:
            self.yaw = float(np.float32(c.get("yaw", 0.0) * np.float32(DEG)))
            self.pitch = float(np.float32(c.get("pitch", 0.0) * np.float32(DEG)))
        self.fov = float(np.float32(c.get("fov", 45.0)) * np.float32(DEG))

    def _materials(self, mats):
        self.material_names = list(mats)  # json keeps file order
        self.materials = []
        for name, m in mats.items():
            self.materials.append({k: m.get(k, v) for k, v in MATERIAL_DEFAULTS.items()})
        self.index = {n: i for i, n in enumerate(self.material_names)}

    def _objects(self, j):
        sph = j.get("spheres", [])
        self.sphere_center = np.array([s["center"] for s in sph], dtype=np.float32).reshape(-1, 3)
        self.sphere_radius = np.array([s["radius"] for s in sph], dtype=np.float32)
        self.sphere_material = np.array([self.index[s["material"]] for s in sph], dtype=np.uint32)
        self.planes = []  # (unit normal, offset, material)
        for p in j.get("planes", []):
            n = np.array(p["normal"], dtype=np.float64)
            n /= np.linalg.norm(n)
            off = p["offset"] if "offset" in p else float(np.dot(n, p["point"]))
            self.planes.append((n, float(off), self.index[p["material"]]))
        # Triangles per material: lists of (positions (T,3,3), normals (T,3,3)).
        self.triangles = {}
        for t in j.get("triangles", []):
            P = np.array(t["vertices"], dtype=np.float64)[None]
            if "normals" in t:
                N = np.array(t["normals"], dtype=np.float64)[None]
                N /= np.linalg.norm(N, axis=2, keepdims=True)
            else:
                fn = np.cross(P[0, 1] - P[0, 0], P[0, 2] - P[0, 0])
                N = np.repeat((fn / np.linalg.norm(fn))[None, None], 3, axis=1)
            self.triangles.setdefault(self.index[t["material"]], []).append((P, N))
        # Meshes: parsed once per file, placed with numpy per (file), many placements at once.
        by_file = {}
        for i, m in enumerate(j.get("meshes", [])):
            f = os.path.normpath(os.path.join(self.dir, m["file"]))
            if os.path.splitext(f)[1].lower() in (".gltf", ".glb", ".ply"):
                raise NotConverted(f"{self.path}: /meshes/{i}/file: glTF and PLY models are not "
                                   f"converted (OBJ is)")
            by_file.setdefault(f, []).append(m)
        for f, ms in by_file.items():
            P0, N0 = read_obj(f)
            M = np.empty((len(ms), 3, 3))
            T = np.empty((len(ms), 3))
            mat = np.empty(len(ms), dtype=np.int64)
            for k, m in enumerate(ms):
                tr = m.get("transform", {})
                s = tr.get("scale", 1.0)
                S = np.diag([s, s, s] if np.isscalar(s) else s).astype(np.float64)
                M[k] = _rotation(tr.get("rotate", [0, 0, 0])) @ S
                T[k] = tr.get("translate", [0, 0, 0])
                mat[k] = self.index[m["material"]]
            NM = np.linalg.inv(M).transpose(0, 2, 1)
            for mi in np.unique(mat):
                sel = mat == mi
                P = np.einsum("nij,tcj->ntci", M[sel], P0) + T[sel][:, None, None, :]
                N = np.einsum("nij,tcj->ntci", NM[sel], N0)
                N /= np.linalg.norm(N, axis=3, keepdims=True)
                self.triangles.setdefault(int(mi), []).append(
                    (P.reshape(-1, 3, 3), N.reshape(-1, 3, 3)))
        self.triangles = {m: (np.concatenate([p for p, _ in v]), np.concatenate([n for _, n in v]))
                          for m, v in self.triangles.items()}

    def _lights(self, ls):
        self.lights = [(np.array(l["position"], dtype=np.float32),
                        np.array(l.get("color", [1, 1, 1]), dtype=np.float32),
                        float(l.get("radius", 0.0))) for l in ls]

    def settings(self, width=None, height=None, bounces=None):
        """The render settings: the scene's defaults, overridden where given. Refuses AA."""
        r = dict(self.render)
        if r["aa"] != 1 or r["adaptive_aa"]:
            raise NotConverted(f"{self.path}: /render/aa: anti-aliasing is not converted "
                               f"(the peer renders one centre sample per pixel)")
        for k, v in (("width", width), ("height", height), ("bounces", bounces)):
            if v is not None:
                r[k] = int(v)
        return r

    def scale(self, k):
        """Scales the scene's geometry, camera and lights by k in place. The image does not
        change (rtlab's shading is scale-free: lights do not fall off, offsets are error bounds);
        with k a power of two no coordinate even rounds differently."""
        self.position = (self.position * np.float32(k)).astype(np.float32)
        self.sphere_center = (self.sphere_center * np.float32(k)).astype(np.float32)
        self.sphere_radius = (self.sphere_radius * np.float32(k)).astype(np.float32)
        self.planes = [(n, off * k, m) for n, off, m in self.planes]
        self.triangles = {m: (P * k, N) for m, (P, N) in self.triangles.items()}
        self.lights = [(p * np.float32(k), c, r * k) for p, c, r in self.lights]

    def counts(self):
        tris = sum(len(p) for p, _ in self.triangles.values())
        return {"spheres": int(len(self.sphere_radius)), "planes": len(self.planes),
                "triangles": int(tris), "lights": len(self.lights),
                "materials": len(self.materials)}

    def transparent(self):
        return any(m["opacity"] < 1 for m in self.materials)

    def bounds(self):
        """Centre and radius of a sphere around the camera, objects and lights."""
        pts = [self.position[None].astype(np.float64)]
        if len(self.sphere_radius):
            pts += [self.sphere_center - self.sphere_radius[:, None],
                    self.sphere_center + self.sphere_radius[:, None]]
        for P, _ in self.triangles.values():
            pts.append(P.reshape(-1, 3))
        pts += [l[0][None] for l in self.lights]
        pts = np.concatenate([np.asarray(p, dtype=np.float64) for p in pts])
        lo, hi = pts.min(0), pts.max(0)
        return (lo + hi) / 2, float(np.linalg.norm(hi - lo) / 2) + 1.0


MAP_NAME = re.compile(r"map-s(\d+)(?:-t(\d+))?-x(\d+)-o(\d+)-m(\d+)(?:-f(\d+)x(\d+))?")
