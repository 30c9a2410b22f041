#!/usr/bin/env python3
"""The metamorphic check of issue 51 on a GPU run of bench/sweeps/acne: for each floor of
scenes/acne/ and each design (row), the frame of the floor as triangles against the frame of the
same floor as a plane, from the run's rows.jsonl and images/*.pfm (a copied-back, unpacked sweep
folder). Prints a Markdown table of pixels more than 2/255 apart (values clamped to [0, 1]); exit
status 1 when any pair has one.

    python3 tools/rtlab_report acne-pairs DIR
"""
import json
import os
import sys

import numpy as np


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3 if kind == b"PF" else 1)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        sys.exit(__doc__)
    d = argv[0]
    rows = [json.loads(line) for line in open(os.path.join(d, "rows.jsonl"))]
    frames = {}
    for r in rows:
        if r.get("status") == "ok" and r.get("image"):
            key = (r["pipeline"], r.get("layout", "-"))
            frames[(r["scene"], key)] = os.path.join(d, r["image"])
    bad = 0
    print(f"device {rows[0]['device']}, driver {rows[0]['driver']}, commit {rows[0]['commit']}\n")
    print("| floor | design | pixels more than 2/255 apart (triangles against plane) |")
    print("|---|---|---:|")
    for (scene, key), path in sorted(frames.items()):
        if not scene.endswith("-tris"):
            continue
        other = frames.get((scene[:-len("-tris")] + "-plane", key))
        if not other:
            continue
        a, b = np.clip(read_pfm(path), 0, 1), np.clip(read_pfm(other), 0, 1)
        over = int(np.any(np.abs(a - b) > 2 / 255, axis=2).sum())
        bad += over > 0
        print(f"| {scene.removeprefix('acne/floor-')[:-5]} | {key[0]} ({key[1]}) | {over} of "
              f"{a.shape[0] * a.shape[1]} |")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
