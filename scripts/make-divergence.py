#!/usr/bin/env python3
"""rtlab — writes the divergence scenes (scenes/README.md, "divergence").

A 8 x 4 grid of spheres and upright quads (two triangles each) over a ground plane, the objects
taking materials in an interleaved order so that neighbouring pixels, and the reflection and
refraction rays of neighbours, run different shading paths. Two knobs make the sweep axes:
  octaves    the noise octaves of every procedural material (the cost knob, 0..64)
  materials  how many distinct materials the objects cycle through (1..16)

  scripts/make-divergence.py                 scenes/divergence.json (4 octaves, 16 materials)
  scripts/make-divergence.py --variants      also scenes/divergence/divergence-o{K}-m{M}.json
"""
import argparse
import json
import pathlib

# 16 materials: the first eight are all different code paths (four noise patterns, a checker,
# a mirror, glass and plain Blinn-Phong); the next eight vary their parameters. With M materials
# the objects use the first M, so M = 1 is one procedural material everywhere.
PALETTE = [
    ("marble", {"diffuse": [0.85, 0.85, 0.8], "diffuse2": [0.2, 0.2, 0.3], "pattern": "marble", "scale": 2}),
    ("mirror", {"diffuse": [0.03, 0.03, 0.03], "specular": [0.8, 0.8, 0.8], "exponent": 200, "reflectance": 0.85}),
    ("granite", {"diffuse": [0.6, 0.55, 0.5], "diffuse2": [0.15, 0.12, 0.12], "pattern": "granite", "scale": 6}),
    ("glass", {"diffuse": [0, 0, 0], "specular": [0.8, 0.8, 0.8], "exponent": 200, "opacity": 0, "ior": 1.5}),
    ("wood", {"diffuse": [0.65, 0.4, 0.2], "diffuse2": [0.35, 0.18, 0.08], "pattern": "wood", "scale": 3}),
    ("bump", {"diffuse": [0.3, 0.5, 0.8], "pattern": "bump", "scale": 4, "bump": 0.4}),
    ("checker", {"diffuse": [0.9, 0.9, 0.9], "diffuse2": [0.1, 0.1, 0.1], "pattern": "checker", "scale": 3}),
    ("plain", {"diffuse": [0.75, 0.2, 0.15]}),
    ("marble2", {"diffuse": [0.3, 0.6, 0.3], "diffuse2": [0.05, 0.15, 0.05], "pattern": "marble", "scale": 5}),
    ("gold", {"diffuse": [0.7, 0.55, 0.2], "specular": [0.8, 0.75, 0.6], "exponent": 80, "reflectance": 0.3}),
    ("granite2", {"diffuse": [0.8, 0.75, 0.7], "diffuse2": [0.3, 0.3, 0.35], "pattern": "granite", "scale": 12}),
    ("tinted", {"diffuse": [0.05, 0.1, 0.05], "specular": [0.8, 0.8, 0.8], "exponent": 150, "opacity": 0.3, "ior": 1.33}),
    ("wood2", {"diffuse": [0.8, 0.6, 0.35], "diffuse2": [0.5, 0.3, 0.15], "pattern": "wood", "scale": 6}),
    ("bump2", {"diffuse": [0.8, 0.75, 0.3], "pattern": "bump", "scale": 8, "bump": 0.25}),
    ("checker2", {"diffuse": [0.8, 0.2, 0.2], "diffuse2": [0.9, 0.9, 0.9], "pattern": "checker", "scale": 8}),
    ("plain2", {"diffuse": [0.2, 0.3, 0.75], "specular": [0.5, 0.5, 0.5], "exponent": 60}),
]
COLUMNS, ROWS = 8, 4


def material(entry, octaves):
    name, m = entry
    m = dict(m, ambient=[0.05, 0.05, 0.05])
    m.setdefault("specular", [0.3, 0.3, 0.3])
    m.setdefault("exponent", 40)
    if "pattern" in m and m["pattern"] != "checker":
        m["octaves"] = octaves
    return name, m


def scene(octaves, count):
    mats = dict(material(e, octaves) for e in PALETTE[:count])
    names = list(mats)
    spheres, triangles = [], []
    for r in range(ROWS):
        for c in range(COLUMNS):
            # Interleaved: neighbours in a row and in a column differ whenever count > 2.
            name = names[(c + 3 * r) % count]
            x, z = (c - (COLUMNS - 1) / 2) * 1.3, 1.5 + r * 1.6
            if (c + r) % 2 == 0:
                spheres.append({"center": [x, 0.55, z], "radius": 0.55, "material": name})
            else:
                a, b = [x - 0.5, 0.05, z], [x + 0.5, 0.05, z]
                cc, d = [x + 0.5, 1.15, z - 0.25], [x - 0.5, 1.15, z - 0.25]
                triangles.append({"vertices": [a, b, cc], "material": name})
                triangles.append({"vertices": [a, cc, d], "material": name})
    return {
        "description": f"issue 15 divergence scene: {COLUMNS}x{ROWS} spheres and quads, "
                       f"{count} distinct materials interleaved, {octaves} noise octaves "
                       "(scripts/make-divergence.py)",
        "camera": {"position": [0, 3.2, -5.5], "look_at": [0, 0.4, 3.5], "fov": 50},
        "materials": mats,
        "spheres": spheres,
        "triangles": triangles,
        "planes": [{"normal": [0, 1, 0], "offset": 0, "material": names[0]}],
        "lights": [{"position": [-4, 8, -3], "color": [0.8, 0.8, 0.8]},
                   {"position": [5, 6, 1], "color": [0.5, 0.5, 0.55]}],
        "render": {"width": 320, "height": 180, "bounces": 4},
    }


def write(path, octaves, count):
    text = json.dumps(scene(octaves, count), indent=1) + "\n"
    path.write_text(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", action="store_true", help="also write the sweep's variants")
    ap.add_argument("--root", default=pathlib.Path(__file__).resolve().parent.parent / "scenes",
                    type=pathlib.Path)
    a = ap.parse_args()
    write(a.root / "divergence.json", 4, 16)
    if a.variants:
        (a.root / "divergence").mkdir(exist_ok=True)
        for o in (0, 2, 4, 8, 16, 32, 64):
            for m in (1, 2, 4, 8, 16):
                write(a.root / "divergence" / f"divergence-o{o}-m{m}.json", o, m)


if __name__ == "__main__":
    main()
