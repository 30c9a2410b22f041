#!/usr/bin/env python3
"""rtlab — writes the crossover-map scenes (scenes/README.md, "map"): a wall of spheres filling a
1920x1080 frame, in front of a backdrop plane, whose knobs are the axes that decide whether a
warp's lanes agree:

  size     the spheres' diameter on screen, in pixels of the frame (1920x1080 unless --frame
           says otherwise; 2 .. 256): how many pixels,
           and so how many lanes of a warp, see the same object
  special  the share of the spheres that are mirrors or glass, half each (0 .. 1), placed at
           random: how much the shapes of neighbouring ray trees differ
  octaves  noise octaves of the procedural materials (0 .. 64): the shading cost
  materials  how many distinct materials the other spheres take at random (1 .. 16)

The sphere count follows from the size: (1920 / size) x (1080 / size), 129,600 spheres at 4 px.
A fixed seed per scene, so the same arguments give the same bytes. Scenes of small spheres are
large (about 10 MB of JSON at 4 px): this writes them where asked (default scenes/map, not
committed) rather than into the checkout's tracked files.

  scripts/make-map.py --size 4 --special 0.5 --octaves 8      one scene
  scripts/make-map.py --grid                                  every scene of bench/sweeps/map
  scripts/make-map.py --grid --sizes 16,64                    a subset of the grid
  scripts/make-map.py --grid --sizes 2,8,32,128 --specials 0,0.1,0.25,0.5,0.75,1 --octaves-list 8
                                                              bench/sweeps/map-dense's scenes
Standard library only.
"""
import argparse
import json
import math
import os
import random

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


def name_of(size, special, octaves, materials, frame=(WIDTH, HEIGHT)):
    name = f"map-s{size}-x{round(special * 100)}-o{octaves}-m{materials}"
    return name if frame == (WIDTH, HEIGHT) else f"{name}-f{frame[0]}x{frame[1]}"


def material(entry, octaves):
    name, m = entry
    m = dict(m, ambient=[0.05, 0.05, 0.05])
    m.setdefault("specular", [0.3, 0.3, 0.3])
    m.setdefault("exponent", 40)
    if "pattern" in m and m["pattern"] != "checker":
        m["octaves"] = octaves
    return name, m


def scene(size, special, octaves, materials, frame=(WIDTH, HEIGHT)):
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
    return {
        "description": f"crossover map: a wall of {len(spheres)} spheres of about {size} px at "
                       f"{width}x{height}, {round(special * 100)}% mirrors and glass, {materials} other "
                       f"materials, {octaves} noise octaves (scripts/make-map.py)",
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, DISTANCE], "fov": FOV},
        "materials": mats,
        "spheres": spheres,
        "planes": [{"normal": [0, 0, -1], "offset": -(DISTANCE + 3 * pitch + 1), "material": plain[0]}],
        "lights": [{"position": [-6, 8, -2], "color": [0.8, 0.8, 0.8]},
                   {"position": [7, 5, 1], "color": [0.5, 0.5, 0.55]}],
        "render": {"width": width, "height": height, "bounces": 4, "accel": "bvh"},
    }


def write(path, data):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w", newline="\n") as f:
        json.dump(data, f, separators=(",", ":"))
        f.write("\n")
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="scenes/map", help="folder for the scenes [scenes/map]")
    ap.add_argument("--size", type=int, default=16, help="sphere diameter in pixels of the frame")
    ap.add_argument("--special", type=float, default=0.5, help="share of mirrors and glass, 0..1")
    ap.add_argument("--octaves", type=int, default=8, help="noise octaves, 0..64")
    ap.add_argument("--materials", type=int, default=16, help="distinct other materials, 1..16")
    ap.add_argument("--grid", action="store_true", help="write every scene of the map's grid")
    ap.add_argument("--sizes", help="with --grid: these sizes instead, e.g. 16,64")
    ap.add_argument("--specials", help="with --grid: these shares instead, e.g. 0,0.1,0.75")
    ap.add_argument("--octaves-list", help="with --grid: these octaves instead, e.g. 0,8")
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
    if a.grid:
        sizes = [int(s) for s in a.sizes.split(",")] if a.sizes else GRID_SIZES
        specials = [float(x) for x in a.specials.split(",")] if a.specials else GRID_SPECIAL
        octaves = [int(o) for o in a.octaves_list.split(",")] if a.octaves_list else GRID_OCTAVES
        combos = [(s, x, o, m) for s in sizes for x in specials for o in octaves
                  for m in GRID_MATERIALS]
    else:
        combos = [(a.size, a.special, a.octaves, a.materials)]
    for combo in combos:
        path = os.path.join(a.out, name_of(*combo, frame) + ".json")
        write(path, scene(*combo, frame))
        print(path)


if __name__ == "__main__":
    main()
