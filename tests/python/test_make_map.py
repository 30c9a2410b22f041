#!/usr/bin/python3
"""Tests of scripts/make-map.py's mesh walls (--shape mesh): the icosphere's triangle count and
shape, the share of mirrors and glass, that a mesh wall keeps the sphere wall's materials, that
bench/sweeps/map-mesh names exactly the grid it writes, and, when the rtlab binary is given
($RTLAB_BIN, as CTest does), that rtlab loads a tiny wall and renders it on the default device.
"""
import collections
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MAKE_MAP = os.path.join(ROOT, "scripts", "make-map.py")
RTLAB = os.environ.get("RTLAB_BIN", "")


def make_map(out, *args):
    """Runs make-map.py into `out`; returns the scene paths it printed."""
    run = subprocess.run([sys.executable, MAKE_MAP, "--out", out, *args], check=True,
                         capture_output=True, text=True)
    return run.stdout.split()


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            kind, *rest = line.split()
            if kind == "v":
                verts.append(tuple(float(x) for x in rest))
            elif kind == "f":
                faces.append(tuple(int(c.split("/")[0]) - 1 for c in rest))
    return verts, faces


class MeshWall(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.out = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def wall(self, *args):
        (path,) = make_map(self.out, *args)
        with open(path) as f:
            return path, json.load(f)

    def test_each_triangle_count_is_a_closed_outward_icosphere(self):
        for triangles, vertices in ((20, 12), (80, 42), (320, 162), (1280, 642)):
            _, scene = self.wall("--shape", "mesh", "--frame", "64x36", "--size", "8",
                                 "--triangles", str(triangles))
            verts, faces = read_obj(os.path.join(self.out, scene["meshes"][0]["file"]))
            self.assertEqual(len(faces), triangles)
            self.assertEqual(len(verts), vertices)
            for v in verts:
                self.assertAlmostEqual(math.sqrt(sum(c * c for c in v)), 1.0, places=5)
            edges = collections.Counter()
            for a, b, c in faces:
                for e in ((a, b), (b, c), (c, a)):
                    edges[tuple(sorted(e))] += 1
                # Counter-clockwise from outside: the face normal points away from the centre.
                p, q, r = verts[a], verts[b], verts[c]
                u = [q[i] - p[i] for i in range(3)]
                w = [r[i] - p[i] for i in range(3)]
                n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                     u[0] * w[1] - u[1] * w[0])
                self.assertGreater(sum(n[i] * (p[i] + q[i] + r[i]) for i in range(3)), 0)
            self.assertEqual(set(edges.values()), {2}, "every edge shared by two faces")
            self.assertEqual(len(verts) - len(edges) + len(faces), 2, "Euler: a sphere")

    def test_a_tiny_wall_places_one_icosphere_per_object(self):
        path, scene = self.wall("--shape", "mesh", "--frame", "64x36", "--size", "8",
                                "--triangles", "80", "--special", "0.5")
        self.assertEqual(os.path.basename(path), "map-s8-t80-x50-o8-m16-f64x36.json")
        self.assertNotIn("spheres", scene)
        meshes = scene["meshes"]
        self.assertEqual(len(meshes), (64 // 8) * (36 // 8))
        self.assertEqual({m["file"] for m in meshes}, {"models/icosphere-t80.obj"})
        for m in meshes:
            self.assertIn(m["material"], scene["materials"])
            self.assertAlmostEqual(m["transform"]["translate"][2], 10.0)
            self.assertGreater(m["transform"]["scale"], 0)

    def test_share_of_mirrors_and_glass(self):
        for special in (0.0, 0.5, 1.0):
            _, scene = self.wall("--shape", "mesh", "--frame", "480x270", "--size", "4",
                                 "--triangles", "20", "--special", str(special))
            kinds = collections.Counter(m["material"] for m in scene["meshes"])
            n = sum(kinds.values())
            self.assertEqual(n, 120 * 67)
            share = (kinds["mirror"] + kinds["glass"]) / n
            self.assertAlmostEqual(share, special, delta=0.02)
            # Half of them each, and the rest among all 16 plain materials.
            self.assertAlmostEqual(kinds["mirror"] / n, special / 2, delta=0.02)
            plain = set(kinds) - {"mirror", "glass"}
            self.assertEqual(len(plain), 0 if special == 1.0 else 16)

    def test_mesh_wall_keeps_the_sphere_walls_materials_and_places(self):
        args = ["--frame", "480x270", "--size", "16", "--special", "0.25", "--octaves", "4"]
        _, spheres = self.wall(*args)
        _, meshes = self.wall("--shape", "mesh", "--triangles", "320", *args)
        self.assertEqual(spheres["materials"], meshes["materials"])
        self.assertEqual([s["material"] for s in spheres["spheres"]],
                         [m["material"] for m in meshes["meshes"]])
        self.assertEqual([s["center"] for s in spheres["spheres"]],
                         [m["transform"]["translate"] for m in meshes["meshes"]])
        self.assertEqual([s["radius"] for s in spheres["spheres"]],
                         [m["transform"]["scale"] for m in meshes["meshes"]])

    def test_bad_triangle_count_is_refused(self):
        run = subprocess.run([sys.executable, MAKE_MAP, "--out", self.out, "--shape", "mesh",
                              "--triangles", "100"], capture_output=True, text=True)
        self.assertNotEqual(run.returncode, 0)
        self.assertIn("--triangles 100: must be one of 20, 80, 320, 1280, 5120", run.stderr)
        self.assertEqual(os.listdir(self.out), [])


class Grid(unittest.TestCase):
    def test_sweep_map_mesh_names_the_grid_and_the_grid_stays_under_the_cap(self):
        with tempfile.TemporaryDirectory() as grid_dir, tempfile.TemporaryDirectory() as sweep_dir:
            grid = make_map(grid_dir, "--shape", "mesh", "--grid")
            swept = make_map(sweep_dir, "--sweep",
                             os.path.join(ROOT, "bench", "sweeps", "map-mesh"))
            names = [os.path.basename(p) for p in grid]
            self.assertEqual(names, [os.path.basename(p) for p in swept])
            self.assertEqual(len(names), 24)
            counts = {}
            for path in grid:
                with open(path) as f:
                    scene = json.load(f)
                triangles = int(scene["meshes"][0]["file"].split("-t")[1].split(".")[0])
                counts[os.path.basename(path)] = len(scene["meshes"]) * triangles
                with open(path) as f, open(os.path.join(sweep_dir, os.path.basename(path))) as g:
                    self.assertEqual(f.read(), g.read(), "--sweep writes the same bytes")
            self.assertEqual(counts["map-s4-t20-x50-o8-m16.json"], 129_600 * 20)
            self.assertEqual(counts["map-s64-t20-x0-o8-m16.json"], 480 * 20)
            self.assertLessEqual(max(counts.values()), 3_000_000)
            self.assertEqual(sorted({n.split("-x")[0] for n in names}),
                             sorted(["map-s4-t20", "map-s16-t20", "map-s16-t80", "map-s16-t320",
                                     "map-s64-t20", "map-s64-t80", "map-s64-t320",
                                     "map-s64-t1280"]))

    def test_sweep_of_the_sphere_map_writes_its_sphere_walls(self):
        with tempfile.TemporaryDirectory() as out:
            paths = make_map(out, "--sweep",
                             os.path.join(ROOT, "bench", "sweeps", "predict-unseen"))
            self.assertEqual(len(paths), 16)
            with open(os.path.join(out, "map-s3-x15-o4-m4.json")) as f:
                scene = json.load(f)
            self.assertEqual(len(scene["spheres"]), 640 * 360)
            self.assertEqual(len(scene["materials"]), 4 + 2)


@unittest.skipUnless(RTLAB and os.access(RTLAB, os.X_OK), "RTLAB_BIN names no rtlab binary")
class Rtlab(unittest.TestCase):
    def test_rtlab_loads_and_renders_a_tiny_mesh_wall(self):
        with tempfile.TemporaryDirectory() as out:
            (path,) = make_map(out, "--shape", "mesh", "--frame", "64x36", "--size", "8",
                               "--triangles", "80", "--special", "0.5")
            run = subprocess.run([RTLAB, "predict", path, "--json"], check=True,
                                 capture_output=True, text=True)
            predicted = json.loads(run.stdout)
            self.assertEqual(predicted["objects"], 32 * 80 + 1, "triangles and the backdrop")
            self.assertEqual((predicted["width"], predicted["height"]), (64, 36))
            png = os.path.join(out, "wall.png")
            subprocess.run([RTLAB, "render", path, "-o", png], check=True, capture_output=True,
                           timeout=300)
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")


if __name__ == "__main__":
    unittest.main()
