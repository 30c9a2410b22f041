#!/usr/bin/env python3
"""Writes scenes/acne/: the self-intersection scenes of issue 51 (core/SHADING.md section 3).
floor-sphere: a sphere over a reflective floor of two triangles, 24 x 24 units, the acceptance
scene (every design within 2/255 of the oracle on at least 99.9% of pixels). floor-<case>-tris and
floor-<case>-plane: the same floor as triangles and as an infinite plane under a camera that
looks down so that the floor fills the frame, which must render alike (the metamorphic test of
tests/oracle_test.cpp, as scene files for GPU runs: bench/sweeps/acne). Python's standard
library only, so that it runs on a GPU host too.

    python3 scripts/make-acne.py [--out scenes/acne]
"""
import argparse
import json
import os

# name: (size, height, centre x, centre z, cells a side, glass, sphere)
FLOORS = {
    "24": (24, 0, 0, 0, 1, False, True),
    "24-high": (24, 3.7, 0, 0, 1, False, False),
    "unit-grid": (1, 0.37, 0, 0, 10, False, True),
    "2000-glass": (2000, -50, 1000, -700, 1, True, False),
    "200-grid-glass": (200, 3.7, 0, 0, 10, True, True),
    "1e5-far": (1e5, 1234.5, 3e5, 2e5, 1, False, True),
}


def floor_scene(size, height, cx, cz, cells, glass, sphere, as_triangles):
    floor = {"ambient": [0.05, 0.05, 0.05], "diffuse": [0.6, 0.55, 0.5],
             "specular": [0.3, 0.3, 0.3], "exponent": 20}
    if glass:
        floor.update(opacity=0.3, ior=1.5)
    else:
        floor.update(reflectance=0.5)
    scene = {
        "description": f"Issue 51: a {size:g}-unit {'glass' if glass else 'mirror'} floor at "
                       f"y = {height:g}, centre ({cx:g}, {cz:g}), as "
                       + (f"{cells} x {cells} squares of two triangles" if as_triangles
                          else "an infinite plane") + (", a sphere over it" if sphere else ""),
        "camera": {"position": [cx, height + 0.15 * size, cz - 0.12 * size], "pitch": -60,
                   "fov": 40},
        "materials": {"floor": floor,
                      "ball": {"ambient": [0.05, 0.05, 0.05], "diffuse": [0.8, 0.2, 0.2],
                               "specular": [0.3, 0.3, 0.3], "exponent": 20}},
        "lights": [{"position": [cx - 0.2 * size, height + 0.4 * size, cz - 0.1 * size],
                    "color": [0.9, 0.9, 0.9], "radius": 0}],
        "render": {"width": 320, "height": 240, "bounces": 2},
    }
    r = 0.03 * size
    if sphere:
        scene["spheres"] = [{"center": [cx, height + 2 * r, cz + 0.05 * size], "radius": r,
                             "material": "ball"}]
    if as_triangles:
        tris, half, step = [], size / 2, size / cells
        for i in range(cells):
            for k in range(cells):
                x0 = cx - half + i * step
                x1 = cx + half if i + 1 == cells else x0 + step
                z0 = cz - half + k * step
                z1 = cz + half if k + 1 == cells else z0 + step
                tris.append({"vertices": [[x0, height, z0], [x1, height, z1], [x1, height, z0]],
                             "material": "floor"})
                tris.append({"vertices": [[x0, height, z0], [x0, height, z1], [x1, height, z1]],
                             "material": "floor"})
        scene["triangles"] = tris
    else:
        scene["planes"] = [{"normal": [0, 1, 0], "point": [cx, height, cz], "material": "floor"}]
    return scene


def floor_sphere():
    return {
        "description": "Issue 51's acceptance scene: a sphere over a reflective floor of two "
                       "triangles, 24 x 24 units, one point light (the offset rule alone "
                       "speckled a third of its pixels in every design and the reference).",
        "camera": {"position": [0, 3, -6], "pitch": -20, "fov": 60},
        "materials": {
            "floor": {"ambient": [0.05, 0.05, 0.05], "diffuse": [0.6, 0.6, 0.6],
                      "specular": [0.3, 0.3, 0.3], "exponent": 20, "reflectance": 0.5},
            "ball": {"ambient": [0.05, 0.02, 0.02], "diffuse": [0.8, 0.2, 0.2],
                     "specular": [0.5, 0.5, 0.5], "exponent": 50}},
        "spheres": [{"center": [0, 1, 2], "radius": 1, "material": "ball"}],
        "triangles": [
            {"vertices": [[-12, 0, -12], [12, 0, -12], [12, 0, 12]], "material": "floor"},
            {"vertices": [[-12, 0, -12], [12, 0, 12], [-12, 0, 12]], "material": "floor"}],
        "lights": [{"position": [-4, 8, -2], "color": [0.9, 0.9, 0.9], "radius": 0}],
        "render": {"width": 320, "height": 180, "bounces": 2},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "scenes",
                                                  "acne"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    files = {"floor-sphere": floor_sphere()}
    for name, f in FLOORS.items():
        files[f"floor-{name}-tris"] = floor_scene(*f, True)
        files[f"floor-{name}-plane"] = floor_scene(*f, False)
    for name, scene in files.items():
        with open(os.path.join(a.out, name + ".json"), "w") as out:
            json.dump(scene, out, indent=1)
            out.write("\n")
    print(f"make-acne: {len(files)} scenes in {os.path.normpath(a.out)}")


if __name__ == "__main__":
    main()
