#!/usr/bin/env python3
"""Writes scenes/models/knot.obj: a (2,3) torus knot tube, smooth and closed, with vertex normals.

The tube follows the knot curve with a Frenet frame (the curvature of a torus knot never
vanishes, and a closed curve gives a periodic frame); each ring has RING vertices and the tube
has SEGMENTS rings, so the model has 2 * SEGMENTS * RING triangles (12,800 by default). Normals
are the analytic tube normals, pointing outward; faces wind counter-clockwise seen from outside.
Floats are printed with 5 significant digits to keep the file small (about 0.8 MB).

Usage: scripts/make-mesh.py [output]   (standard library only; default scenes/models/knot.obj)
"""
import math
import os
import sys

P, Q = 2, 3            # winds P times around the axis, Q times through the hole
R_MAJOR, R_MINOR = 1.0, 0.4
TUBE = 0.18            # tube radius
SEGMENTS, RING = 400, 16


def curve(t):
    r = R_MAJOR + R_MINOR * math.cos(Q * t)
    return (r * math.cos(P * t), r * math.sin(P * t), -R_MINOR * math.sin(Q * t))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def normalize(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "models", "knot.obj")
    h = 1e-4
    verts, norms = [], []
    for i in range(SEGMENTS):
        t = 2 * math.pi * i / SEGMENTS
        c, ca, cb = curve(t), curve(t - h), curve(t + h)
        tangent = normalize(sub(cb, ca))
        accel = sub(tuple(x + y for x, y in zip(ca, cb)), tuple(2 * x for x in c))
        binormal = normalize(cross(tangent, accel))
        normal = cross(binormal, tangent)
        for j in range(RING):
            a = 2 * math.pi * j / RING
            n = tuple(math.cos(a) * x + math.sin(a) * y for x, y in zip(normal, binormal))
            verts.append(tuple(p + TUBE * d for p, d in zip(c, n)))
            norms.append(n)

    def index(i, j):
        return (i % SEGMENTS) * RING + (j % RING) + 1

    faces = []
    for i in range(SEGMENTS):
        for j in range(RING):
            a, b, c, d = index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)
            faces += [(a, b, c), (a, c, d)]
    # Wind counter-clockwise around the outward normal.
    v0, v1, v2 = (verts[k - 1] for k in faces[0])
    if dot(cross(sub(v1, v0), sub(v2, v0)), norms[faces[0][0] - 1]) < 0:
        faces = [(a, c, b) for a, b, c in faces]

    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        f.write("# (%d,%d) torus knot tube, %d triangles, made by scripts/make-mesh.py\n"
                % (P, Q, len(faces)))
        for v in verts:
            f.write("v %.5g %.5g %.5g\n" % v)
        for n in norms:
            f.write("vn %.5g %.5g %.5g\n" % n)
        for a, b, c in faces:
            f.write("f %d//%d %d//%d %d//%d\n" % (a, a, b, b, c, c))
    print("%s: %d vertices, %d triangles" % (out, len(verts), len(faces)))


if __name__ == "__main__":
    main()
