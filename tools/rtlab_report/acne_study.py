#!/usr/bin/env python3
"""The acne study of issue 51: a sphere over a reflective floor of two triangles, scaled by 1e-4, 1
and 1e5, rendered with each --offset rule by one or two rtlab binaries (before and after a
change), each image scored against the independent oracle (`--pipeline oracle` of the after
binary) by OpenImageIO's oiiotool and idiff. Writes a Markdown table of acne rates (pixels more
than 2/255 off the oracle in some channel, values clamped to [0, 1]) per pipeline.

    python3 tools/rtlab_report acne-study [--before BIN] [--after BIN] [--pipelines mega,cpu] [--size 320x180]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

# The acceptance scene of issue 51, as scripts/make-acne.py writes it.
FLOOR_SPHERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes",
                            "acne", "floor-sphere.json")


def scaled(scene, k):
    """The scene with every length multiplied by k (angles and colours kept)."""
    s = json.loads(json.dumps(scene))
    s["camera"]["position"] = [k * v for v in s["camera"]["position"]]
    for sp in s["spheres"]:
        sp["center"] = [k * v for v in sp["center"]]
        sp["radius"] *= k
    for t in s["triangles"]:
        t["vertices"] = [[k * v for v in p] for p in t["vertices"]]
    for light in s["lights"]:
        light["position"] = [k * v for v in light["position"]]
    return s


def render(binary, scene_file, pipeline, offset, size, out):
    """Renders to out (.exr, clamped to [0, 1] by OpenImageIO's oiiotool); an error line or None."""
    raw = out[:-4] + "-raw.exr"
    r = subprocess.run([binary, "render", scene_file, "--pipeline", pipeline, "--offset", offset,
                        "--size", size, "-o", raw], capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        return (r.stderr.strip().splitlines() or ["failed"])[-1]
    subprocess.run(["oiiotool", raw, "--clamp:min=0:max=1", "-o", out], check=True, timeout=60)
    return None


def acne_rate(image, oracle):
    """Share of pixels with a channel more than 2/255 off (OpenImageIO's idiff)."""
    r = subprocess.run(["idiff", "-v", "-fail", "0.0078431", "-failpercent", "100", "-warn", "1",
                        image, oracle], capture_output=True, text=True, timeout=60)
    m = re.search(r"\d+ pixels \(([\d.e+-]+)%\) over 0.0078431", r.stdout)
    return float(m.group(1)) / 100 if m else 0.0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="rtlab binary before the change")
    ap.add_argument("--after", default="build/bin/rtlab", help="rtlab binary after it")
    ap.add_argument("--pipelines", default="cpu,mega,queue")
    ap.add_argument("--size", default="320x180")
    a = ap.parse_args(argv)
    pipes = a.pipelines.split(",")
    runs = [("before", a.before), ("after", a.after)] if a.before else [("after", a.after)]
    print("| scale | offset | " + " | ".join(f"{w} {p}" for w, _ in runs for p in pipes) + " |")
    print("|---|---|" + "---|" * (len(runs) * len(pipes)))
    with open(FLOOR_SPHERE) as f:
        scene = json.load(f)
    with tempfile.TemporaryDirectory() as tmp:
        for k in (1e-4, 1.0, 1e5):
            path = os.path.join(tmp, f"floor-sphere-{k:g}.json")
            with open(path, "w") as f:
                json.dump(scaled(scene, k), f)
            oracle = os.path.join(tmp, "oracle.exr")
            err = render(a.after, path, "oracle", "bound", a.size, oracle)
            if err:
                sys.exit(f"acne-study: the oracle failed: {err}")
            for offset in ("fixed", "scaled", "bound"):
                cells = []
                for when, binary in runs:
                    for p in pipes:
                        img = os.path.join(tmp, f"{when}-{p}.exr")
                        err = render(binary, path, p, offset, a.size, img)
                        cells.append(err or f"{100 * acne_rate(img, oracle):.1f}%")
                print(f"| {k:g} | {offset} | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
