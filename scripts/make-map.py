#!/usr/bin/env python3
"""rtlab — writes the crossover-map scenes (scenes/README.md, "map"): a wall of spheres (or of
triangle meshes, --shape mesh) filling a 1920x1080 frame, in front of a backdrop plane, whose
knobs are the axes that decide whether a warp's lanes agree:

  size     the spheres' diameter on screen, in pixels of the frame (1920x1080 unless --frame
           says otherwise; 2 .. 256): how many pixels,
           and so how many lanes of a warp, see the same object
  special  the share of the spheres that are mirrors or glass, half each (0 .. 1), placed at
           random: how much the shapes of neighbouring ray trees differ
  octaves  noise octaves of the procedural materials (0 .. 64): the shading cost
  materials  how many distinct materials the other spheres take at random (1 .. 16)
  triangles  with --shape mesh: each object is an icosphere of 20, 80, 320, 1280 or 5120
           triangles (0 to 4 subdivisions) in place of the sphere: the primitive count, and
           how many primitives a warp's rays meet

The object count follows from the size: (1920 / size) x (1080 / size), 129,600 objects at 4 px.
A fixed seed per scene, so the same arguments give the same bytes; a mesh wall draws the same
materials, in the same places, as the sphere wall of the same size, share, octaves and materials.
Mesh walls place one icosphere OBJ per triangle count (written beside the scenes, in
models/icosphere-t<N>.obj) once per object through the scene's "meshes" (a translation and a
scale), so each object keeps its own material and the files stay small; the loader reads each
OBJ once. Scenes of small objects are large (about 10 MB of JSON for spheres and 14 MB for
meshes at 4 px): this writes them where asked (default scenes/map, not committed) rather than
into the checkout's tracked files.

  scripts/make-map.py --size 4 --special 0.5 --octaves 8      one scene
  scripts/make-map.py --grid                                  every scene of bench/sweeps/map
  scripts/make-map.py --grid --sizes 16,64                    a subset of the grid
  scripts/make-map.py --grid --sizes 2,8,32,128 --specials 0,0.1,0.25,0.5,0.75,1 --octaves-list 8
                                                              bench/sweeps/map-dense's scenes
  scripts/make-map.py --shape mesh --size 16 --triangles 320  one wall of icospheres
  scripts/make-map.py --shape mesh --grid                     every scene of bench/sweeps/map-mesh
  scripts/make-map.py --sweep bench/sweeps/map-mesh           the map scenes a sweep file names
Standard library only.
"""
import argparse
import json
import math
import os
import random
import re
import sys

WIDTH, HEIGHT = 1920, 1080
FOV = 40.0                       # vertical field of view, degrees
DISTANCE = 10.0                  # camera to wall
PLAIN = [
    ("plain", {"diffuse": [0.75, 0.2, 0.15]}),
    ("marble", {"diffuse": [0.85, 0.85, 0.8], "diffuse2": [0.2, 0.2, 0.3], "pattern": "marble", "scale": 2}),
    ("granite", {"diffuse": [0.6, 0.55, 0.5], "diffuse2": [0.15, 0.12, 0.12], "pattern": "granite", "scale": 6}),
    ("wood", {"diffuse": [0.65, 0.4, 0.2], "diffuse2": [0.35, 0.18, 0.08], "pattern": "wood", "scale": 3}),
    ("bump", {"diffuse": [0.3, 0.5, 0.8], "pattern": "bump", "scale": 4, "bump": 0.4}),
    ("checker", {"diffuse": [0.9, 0.9, 0.9], "diffuse2": [0.1, 0.1, 0.1], "pattern": "checker", "scale": 3}),
    ("plain2", {"diffuse": [0.2, 0.3, 0.75], "specular": [0.5, 0.5, 0.5], "exponent": 60}),
    ("marble2", {"diffuse": [0.3, 0.6, 0.3], "diffuse2": [0.05, 0.15, 0.05], "pattern": "marble", "scale": 5}),
    ("gold", {"diffuse": [0.7, 0.55, 0.2], "specular": [0.8, 0.75, 0.6], "exponent": 80, "reflectance": 0.3}),
    ("granite2", {"diffuse": [0.8, 0.75, 0.7], "diffuse2": [0.3, 0.3, 0.35], "pattern": "granite", "scale": 12}),
    ("wood2", {"diffuse": [0.8, 0.6, 0.35], "diffuse2": [0.5, 0.3, 0.15], "pattern": "wood", "scale": 6}),
    ("bump2", {"diffuse": [0.8, 0.75, 0.3], "pattern": "bump", "scale": 8, "bump": 0.25}),
    ("checker2", {"diffuse": [0.8, 0.2, 0.2], "diffuse2": [0.9, 0.9, 0.9], "pattern": "checker", "scale": 8}),
    ("plain3", {"diffuse": [0.5, 0.5, 0.5], "specular": [0.3, 0.3, 0.3], "exponent": 20}),
    ("marble3", {"diffuse": [0.8, 0.5, 0.6], "diffuse2": [0.3, 0.1, 0.2], "pattern": "marble", "scale": 9}),
    ("granite3", {"diffuse": [0.4, 0.45, 0.5], "diffuse2": [0.1, 0.1, 0.15], "pattern": "granite", "scale": 3}),
]
MIRROR = {"diffuse": [0.03, 0.03, 0.03], "specular": [0.8, 0.8, 0.8], "exponent": 200, "reflectance": 0.85}
GLASS = {"diffuse": [0, 0, 0], "specular": [0.8, 0.8, 0.8], "exponent": 200, "opacity": 0, "ior": 1.5}
# The map's grid (bench/sweeps/map lists the same names).
GRID_SIZES = [4, 16, 64, 256]
GRID_SPECIAL = [0.0, 0.25, 0.5, 1.0]
GRID_OCTAVES = [0, 8]
GRID_MATERIALS = [16]
# The mesh map's grid (bench/sweeps/map-mesh): every size and triangle count whose wall stays
# under MESH_MAX_TRIANGLES, so that each scene loads and builds its BVH in seconds.
MESH_GRID_SIZES = [4, 16, 64]
MESH_GRID_TRIANGLES = [20, 80, 320, 1280]
MESH_GRID_SPECIAL = [0.0, 0.5, 1.0]
MESH_GRID_OCTAVES = [8]
MESH_MAX_TRIANGLES = 3_000_000
ICOSPHERE_TRIANGLES = [20 * 4 ** k for k in range(5)]  # 0 to 4 subdivisions
NAME = re.compile(r"map-s(\d+)(?:-t(\d+))?-x(\d+)-o(\d+)-m(\d+)(?:-f(\d+)x(\d+))?")


def name_of(size, special, octaves, materials, frame=(WIDTH, HEIGHT), triangles=None):
    mesh = f"-t{triangles}" if triangles else ""
    name = f"map-s{size}{mesh}-x{round(special * 100)}-o{octaves}-m{materials}"
    return name if frame == (WIDTH, HEIGHT) else f"{name}-f{frame[0]}x{frame[1]}"


def parse_name(name):
    """The arguments name_of was given, from a scene's name; None if it is no map scene."""
    m = NAME.fullmatch(name)
    if not m:
        return None
    size, triangles, x, octaves, materials, fw, fh = m.groups()
    frame = (int(fw), int(fh)) if fw else (WIDTH, HEIGHT)
    return (int(size), int(x) / 100, int(octaves), int(materials), frame,
            int(triangles) if triangles else None)


def objects_of(size, frame=(WIDTH, HEIGHT)):
    return (frame[0] // size) * (frame[1] // size)


def icosphere(triangles):
    """Vertices on the unit sphere and faces (index triples, counter-clockwise seen from
    outside) of an icosahedron subdivided until it has `triangles` faces: each edge split at its
    midpoint, pushed out to the sphere."""
    t = (1 + math.sqrt(5)) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(1 + t * t) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    while len(faces) < triangles:
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(u + v) / 2 for u, v in zip(verts[a], verts[b])]
                n = math.sqrt(sum(c * c for c in p))
                verts.append(tuple(c / n for c in p))
                mid[key] = len(verts) - 1
            return mid[key]

        split = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = split
    return verts, faces


def icosphere_obj(triangles):
    """OBJ text of the unit icosphere, with its vertex normals (the vertices themselves) so that
    it shades as a smooth sphere and only its outline and the rays' hit points are faceted."""
    verts, faces = icosphere(triangles)
    lines = [f"# unit icosphere, {len(faces)} triangles (scripts/make-map.py)"]
    lines += ["v %.6f %.6f %.6f" % v for v in verts]
    lines += ["vn %.6f %.6f %.6f" % v for v in verts]
    lines += [f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


def check_triangles(triangles):
    if triangles not in ICOSPHERE_TRIANGLES:
        raise SystemExit(f"--triangles {triangles}: must be one of "
                         f"{', '.join(map(str, ICOSPHERE_TRIANGLES))}")


def mesh_file(triangles):
    return f"models/icosphere-t{triangles}.obj"


def material(entry, octaves):
    name, m = entry
    m = dict(m, ambient=[0.05, 0.05, 0.05])
    m.setdefault("specular", [0.3, 0.3, 0.3])
    m.setdefault("exponent", 40)
    if "pattern" in m and m["pattern"] != "checker":
        m["octaves"] = octaves
    return name, m


def scene(size, special, octaves, materials, frame=(WIDTH, HEIGHT), triangles=None):
    """The scene's JSON: spheres, or with `triangles` one icosphere mesh of that many triangles
    in each sphere's place (the same centre, material and radius)."""
    if triangles is not None:
        check_triangles(triangles)
    if not 1 <= materials <= len(PLAIN):
        raise SystemExit(f"--materials {materials}: must be in 1..{len(PLAIN)}")
    if not 0 <= special <= 1:
        raise SystemExit(f"--special {special}: must be in 0..1")
    width, height = frame
    if not 2 <= size <= height // 2:
        raise SystemExit(f"--size {size}: must be in 2..{height // 2} pixels at {width}x{height}")
    rng = random.Random(f"{size}/{special}/{octaves}/{materials}")
    mats = dict(material(e, octaves) for e in PLAIN[:materials])
    mats["mirror"] = MIRROR
    mats["glass"] = GLASS
    plain = list(mats)[:materials]
    # The wall at z = DISTANCE spans the frame: height 2 d tan(fov / 2), one pixel is that over
    # the frame's height.
    view_h = 2 * DISTANCE * math.tan(math.radians(FOV / 2))
    pixel = view_h / height
    pitch = size * pixel
    cols, rows = width // size, height // size
    spheres = []
    for r in range(rows):
        for c in range(cols):
            x = (c - (cols - 1) / 2) * pitch
            y = (r - (rows - 1) / 2) * pitch
            u = rng.random()
            m = ("mirror" if u < special / 2 else "glass") if u < special else rng.choice(plain)
            spheres.append({"center": [round(x, 5), round(y, 5), DISTANCE],
                            "radius": round(0.48 * pitch, 6), "material": m})
    objects = {"spheres": spheres}
    what = f"{len(spheres)} spheres"
    if triangles:
        objects = {"meshes": [{"file": mesh_file(triangles), "material": o["material"],
                               "transform": {"translate": o["center"], "scale": o["radius"]}}
                              for o in spheres]}
        what = (f"{len(spheres)} icospheres of {triangles} triangles "
                f"({len(spheres) * triangles:,} in all)")
    return {
        "description": f"crossover map: a wall of {what} of about {size} px at "
                       f"{width}x{height}, {round(special * 100)}% mirrors and glass, {materials} other "
                       f"materials, {octaves} noise octaves (scripts/make-map.py)",
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, DISTANCE], "fov": FOV},
        "materials": mats,
        **objects,
        "planes": [{"normal": [0, 0, -1], "offset": -(DISTANCE + 3 * pitch + 1), "material": plain[0]}],
        "lights": [{"position": [-6, 8, -2], "color": [0.8, 0.8, 0.8]},
                   {"position": [7, 5, 1], "color": [0.5, 0.5, 0.55]}],
        "render": {"width": width, "height": height, "bounces": 4, "accel": "bvh"},
    }


def write(path, data):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w", newline="\n") as f:
        if isinstance(data, str):
            f.write(data)
        else:
            json.dump(data, f, separators=(",", ":"))
            f.write("\n")
    os.replace(tmp, path)  # readers never see a half-written file


def sweep_scenes(path):
    """The map scenes a sweep file names (`map/<name>` in its scenes lines), as name_of's
    arguments, in file order and each once."""
    combos = []
    with open(path) as f:
        for line in f:
            key, _, value = line.split("#")[0].partition("=")
            if key.strip() != "scenes":
                continue
            for token in value.replace(",", " ").split():
                name = token[len("map/"):] if token.startswith("map/") else None
                if name is None:
                    continue
                combo = parse_name(name)
                if combo is None:
                    raise SystemExit(f"{path}: {token}: not a name make-map.py writes")
                if combo not in combos:
                    combos.append(combo)
    return combos


def grid(a, frame):
    """The combinations --grid asks for; mesh walls over --max-triangles are left out (and said
    so), since one at 4 px and 80 triangles an object would hold ten million."""
    mesh = a.shape == "mesh"
    lists = lambda text, kind, default: [kind(v) for v in text.split(",")] if text else default
    sizes = lists(a.sizes, int, MESH_GRID_SIZES if mesh else GRID_SIZES)
    specials = lists(a.specials, float, MESH_GRID_SPECIAL if mesh else GRID_SPECIAL)
    octaves = lists(a.octaves_list, int, MESH_GRID_OCTAVES if mesh else GRID_OCTAVES)
    triangles = lists(a.triangles_list, int, MESH_GRID_TRIANGLES) if mesh else [None]
    combos = []
    for s in sizes:
        for t in triangles:
            if t and objects_of(s, frame) * t > a.max_triangles:
                print(f"make-map.py: {s} px, {t} triangles an object: "
                      f"{objects_of(s, frame) * t:,} triangles, over --max-triangles "
                      f"{a.max_triangles:,}; left out", file=sys.stderr)
                continue
            combos += [(s, x, o, m, frame, t) for x in specials for o in octaves
                       for m in GRID_MATERIALS]
    return combos


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="scenes/map", help="folder for the scenes [scenes/map]")
    ap.add_argument("--shape", choices=["sphere", "mesh"], default="sphere",
                    help="the wall's objects: spheres, or icosphere meshes [sphere]")
    ap.add_argument("--size", type=int, default=16, help="object diameter in pixels of the frame")
    ap.add_argument("--special", type=float, default=0.5, help="share of mirrors and glass, 0..1")
    ap.add_argument("--octaves", type=int, default=8, help="noise octaves, 0..64")
    ap.add_argument("--materials", type=int, default=16, help="distinct other materials, 1..16")
    ap.add_argument("--triangles", type=int, default=320,
                    help="with --shape mesh: triangles an object, "
                         f"{', '.join(map(str, ICOSPHERE_TRIANGLES))} [%(default)s]")
    ap.add_argument("--grid", action="store_true", help="write every scene of the map's grid "
                    "(with --shape mesh, the mesh map's)")
    ap.add_argument("--sizes", help="with --grid: these sizes instead, e.g. 16,64")
    ap.add_argument("--specials", help="with --grid: these shares instead, e.g. 0,0.1,0.75")
    ap.add_argument("--octaves-list", help="with --grid: these octaves instead, e.g. 0,8")
    ap.add_argument("--triangles-list", help="with --grid --shape mesh: these triangle counts "
                    "instead, e.g. 20,1280")
    ap.add_argument("--max-triangles", type=int, default=MESH_MAX_TRIANGLES,
                    help="with --grid --shape mesh: leave out walls of more triangles "
                         "[%(default)s]")
    ap.add_argument("--sweep", metavar="FILE", action="append",
                    help="write every map scene this sweep file names, whatever its shape "
                         "(may repeat)")
    ap.add_argument("--frame", default=f"{WIDTH}x{HEIGHT}",
                    help="the frame WxH the wall fills and sizes are measured in; other than "
                         f"{WIDTH}x{HEIGHT}, names end in -fWxH [%(default)s]")
    a = ap.parse_args()
    try:
        frame = tuple(int(v) for v in a.frame.lower().split("x"))
        if len(frame) != 2 or min(frame) < 4:
            raise ValueError
    except ValueError:
        raise SystemExit(f"--frame {a.frame}: expected WxH, e.g. 480x270")
    if a.sweep and a.grid:
        raise SystemExit("--sweep and --grid: give one")
    if a.sweep:
        combos = [c for path in a.sweep for c in sweep_scenes(path)]
    elif a.grid:
        combos = grid(a, frame)
    else:
        triangles = a.triangles if a.shape == "mesh" else None
        combos = [(a.size, a.special, a.octaves, a.materials, frame, triangles)]
    for t in sorted({c[5] for c in combos if c[5]}):
        check_triangles(t)  # before anything is written
        write(os.path.join(a.out, mesh_file(t)), icosphere_obj(t))
    for combo in combos:
        path = os.path.join(a.out, name_of(*combo) + ".json")
        write(path, scene(*combo))
        print(path)


if __name__ == "__main__":
    main()
