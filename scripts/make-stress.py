#!/usr/bin/env python3
"""Writes the stress scenes of the acceleration structures, each 1280x720 with mirrors and glass:

  many-spheres.json   a field of 320 x 320 = 102,400 spheres (diffuse, mirror and glass) on a
                      ground plane, with a large mirror and a large glass sphere in front
  big-mesh.json       a terrain of 2 x 708^2 = 1,002,528 triangles (models/big-mesh.obj) under a
                      transparent water plane, with a mirror and a glass sphere above it

The files are large (about 7 MB of JSON and 35 MB of OBJ) and are not committed: run this
script, or let the tests generate them into the build folder. Everything is deterministic (a
fixed seed and closed-form heights), so the same arguments always give the same bytes.

Usage: scripts/make-stress.py [--out DIR] [--side N] [--terrain N] [--only spheres|mesh]
  --out      folder for the scenes (default scenes/stress); the OBJ goes to DIR/models/
  --side     spheres per side of the field (default 320: 102,400 spheres)
  --terrain  quads per side of the terrain (default 708: 1,002,528 triangles)
Standard library only.
"""
import argparse
import math
import os
import random

FIELD_SPACING = 1.0  # distance between neighbouring sphere centres
TERRAIN_SIZE = 100.0  # terrain spans [-50, 50] in x and z
WATER_LEVEL = 0.6


def write(path, text):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w", newline="\n") as f:
        f.write(text)
    os.replace(tmp, path)  # readers never see a half-written file


def num(x):
    return f"{x:.4f}".rstrip("0").rstrip(".") if x != 0 else "0"


def vec(v):
    return "[" + ", ".join(num(x) for x in v) + "]"


MATERIALS = """  "materials": {
    "ground": {"ambient": [0.05, 0.05, 0.05], "diffuse": [0.55, 0.55, 0.5], "exponent": 8},
    "red": {"ambient": [0.06, 0.02, 0.02], "diffuse": [0.75, 0.18, 0.12], "specular": [0.4, 0.4, 0.4], "exponent": 40},
    "green": {"ambient": [0.02, 0.06, 0.02], "diffuse": [0.2, 0.65, 0.2], "specular": [0.4, 0.4, 0.4], "exponent": 40},
    "blue": {"ambient": [0.02, 0.02, 0.06], "diffuse": [0.15, 0.25, 0.75], "specular": [0.4, 0.4, 0.4], "exponent": 40},
    "gold": {"ambient": [0.06, 0.05, 0.02], "diffuse": [0.7, 0.55, 0.2], "specular": [0.8, 0.75, 0.6], "exponent": 80, "reflectance": 0.3},
    "mirror": {"diffuse": [0.03, 0.03, 0.03], "specular": [0.8, 0.8, 0.8], "exponent": 200, "reflectance": 0.9},
    "glass": {"diffuse": [0, 0, 0], "specular": [0.8, 0.8, 0.8], "exponent": 200, "opacity": 0, "ior": 1.5}"""


def many_spheres(out, side):
    rng = random.Random(5)
    kinds = ["red", "green", "blue", "gold", "red", "green", "blue", "mirror", "glass"]
    half = (side - 1) * FIELD_SPACING / 2
    spheres = []
    for i in range(side):
        for j in range(side):
            r = rng.uniform(0.15, 0.42)
            x = -half + i * FIELD_SPACING + rng.uniform(-0.05, 0.05)
            z = -half + j * FIELD_SPACING + rng.uniform(-0.05, 0.05)
            m = kinds[rng.randrange(len(kinds))]
            spheres.append(f'    {{"center": {vec((x, r, z))}, "radius": {num(r)}, "material": "{m}"}}')
    # Two large spheres in front of the camera, on the near edge of the field.
    near = -half - 3.0
    spheres.append(f'    {{"center": {vec((-2.2, 1.6, near))}, "radius": 1.6, "material": "mirror"}}')
    spheres.append(f'    {{"center": {vec((2.2, 1.6, near))}, "radius": 1.6, "material": "glass"}}')
    camera = (0.0, 6.0, near - 9.0)
    text = "{\n"
    text += f'  "description": "Stress scene (scripts/make-stress.py): {side * side + 2} spheres on a plane, with a large mirror and glass sphere in front.",\n'
    text += f'  "camera": {{"position": {vec(camera)}, "look_at": {vec((0, 0, near + 25))}, "fov": 50}},\n'
    text += MATERIALS + "\n  },\n"
    text += '  "spheres": [\n' + ",\n".join(spheres) + "\n  ],\n"
    text += '  "planes": [{"normal": [0, 1, 0], "offset": 0, "material": "ground"}],\n'
    text += '  "lights": [\n'
    text += f'    {{"position": {vec((-half * 0.6, 40, -half * 0.8))}, "color": [0.9, 0.88, 0.8]}},\n'
    text += f'    {{"position": {vec((half, 25, 0))}, "color": [0.3, 0.3, 0.4]}}\n'
    text += "  ],\n"
    text += '  "render": {"width": 1280, "height": 720, "bounces": 3}\n}\n'
    write(os.path.join(out, "many-spheres.json"), text)
    return side * side + 2


def height(x, z):
    """Closed-form rolling hills with ridges: a few octaves of rotated sines."""
    h = 0.0
    amp, freq, angle = 6.0, 0.045, 0.3
    for _ in range(6):
        c, s = math.cos(angle), math.sin(angle)
        u, v = c * x - s * z, s * x + c * z
        h += amp * math.sin(freq * u + 1.3) * math.cos(freq * 0.8 * v + 0.4)
        amp *= 0.45
        freq *= 2.1
        angle += 1.1
    # Fall towards the water on the far side so the lake has a shore.
    return h + 0.04 * z


def big_mesh(out, n):
    step = TERRAIN_SIZE / n
    half = TERRAIN_SIZE / 2
    lines = []
    for i in range(n + 1):
        z = -half + i * step
        for j in range(n + 1):
            x = -half + j * step
            lines.append(f"v {x:.4f} {height(x, z):.4f} {z:.4f}")
    row = n + 1
    for i in range(n):
        for j in range(n):
            a = i * row + j + 1  # OBJ indices start at 1
            b, c, d = a + 1, a + row, a + row + 1
            # Counter-clockwise seen from above (+y), so geometric normals point up.
            lines.append(f"f {a} {c} {b}")
            lines.append(f"f {b} {c} {d}")
    obj = f"# Terrain of scripts/make-stress.py: {n}x{n} quads, {2 * n * n} triangles\n"
    write(os.path.join(out, "models", "big-mesh.obj"), obj + "\n".join(lines) + "\n")

    camera = (-30.0, 14.0, -44.0)
    text = "{\n"
    text += f'  "description": "Stress scene (scripts/make-stress.py): a terrain of {2 * n * n} triangles under a water plane, a mirror and a glass sphere.",\n'
    text += f'  "camera": {{"position": {vec(camera)}, "look_at": [0, 0, 0], "fov": 55}},\n'
    text += MATERIALS + ",\n"
    text += '    "terrain": {"ambient": [0.05, 0.06, 0.04], "diffuse": [0.45, 0.55, 0.3], "specular": [0.1, 0.1, 0.1], "exponent": 16},\n'
    text += '    "water": {"ambient": [0, 0.01, 0.02], "diffuse": [0.05, 0.15, 0.2], "specular": [0.9, 0.9, 0.9], "exponent": 300, "opacity": 0.25, "ior": 1.33}\n'
    text += "  },\n"
    text += '  "meshes": [{"file": "models/big-mesh.obj", "material": "terrain"}],\n'
    text += f'  "planes": [{{"normal": [0, 1, 0], "offset": {WATER_LEVEL}, "material": "water"}}],\n'
    text += '  "spheres": [\n'
    text += f'    {{"center": {vec((-8, height(-8, -10) + 5, -10))}, "radius": 3, "material": "mirror"}},\n'
    text += f'    {{"center": {vec((-18, height(-18, -22) + 4, -22))}, "radius": 2.5, "material": "glass"}}\n'
    text += "  ],\n"
    text += '  "lights": [\n'
    text += '    {"position": [-60, 80, -20], "color": [0.95, 0.92, 0.85]},\n'
    text += '    {"position": [40, 30, -60], "color": [0.25, 0.25, 0.3]}\n'
    text += "  ],\n"
    text += '  "render": {"width": 1280, "height": 720, "bounces": 3}\n}\n'
    write(os.path.join(out, "big-mesh.json"), text)
    return 2 * n * n


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join(here, "..", "scenes", "stress"))
    p.add_argument("--side", type=int, default=320)
    p.add_argument("--terrain", type=int, default=708)
    p.add_argument("--only", choices=["spheres", "mesh"])
    a = p.parse_args()
    if a.side < 1 or a.terrain < 1:
        p.error("--side and --terrain must be positive")
    if a.only != "mesh":
        print(f"{os.path.join(a.out, 'many-spheres.json')}: {many_spheres(a.out, a.side)} spheres")
    if a.only != "spheres":
        print(f"{os.path.join(a.out, 'big-mesh.json')}: {big_mesh(a.out, a.terrain)} triangles")


if __name__ == "__main__":
    main()
