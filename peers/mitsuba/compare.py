#!/usr/bin/env python3
"""The Mitsuba peer's image against rtlab's, per scene (issue 53, "same images").

For each scene: rtlab renders it (`rtlab render SCENE --pipeline cpu`, the double-precision
oracle, or any --pipeline) to linear EXR, the peer (whitted.py) renders it in each asked Dr.Jit
mode, and both are compared as core/SHADING.md section 10 says: linear values clamped to [0, 1],
in units of 1/255. One JSON row per scene and mode: the share of pixels whose every channel is
within 2/255, the mean and max error, and how many pixels are off by more than 2/255 and by
more than 32/255. Scenes the peer does not convert give a row with "not_converted" and the
reason. Exit status 1 when a row misses --min-within (the tests' gate), else 0.

  compare.py scenes/cornell.json scenes/spheres.json --size 160x120 [--bounces B]
             [--modes symbolic,evaluated] [--variant llvm_ad_rgb] [--rtlab PATH]
             [--pipeline cpu] [--out DIR] [--min-within 0.99]
  compare.py SCENES --variant cuda_ad_rgb --no-reference --out DIR   (a GPU host without rtlab:
             the peer's EXRs only), then here: compare.py SCENES --peer-images DIR
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import whitted  # noqa: E402
from rtlab_scene import NotConverted, Scene  # noqa: E402


def find_rtlab(given=None):
    for cand in (given, os.environ.get("RTLAB_BIN"), "/work/rtlab-bin/rtlab",
                 os.path.join(ROOT, "build", "bin", "rtlab")):
        if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
    raise SystemExit("compare.py: no rtlab binary (give --rtlab or set RTLAB_BIN)")


def read_exr(path):
    bmp = whitted.mi.Bitmap(path)
    img = np.array(bmp, dtype=np.float32)
    return img[..., :3]


def errors(a, b):
    """Per-pixel error in 1/255 (max over channels) of linear values clamped to [0, 1]."""
    e = np.abs(np.clip(a, 0, 1) - np.clip(b, 0, 1)).max(axis=-1) * 255.0
    return {"within_2": float((e <= 2.0).mean()), "mean": float(e.mean()),
            "max": float(e.max()), "over_2": int((e > 2.0).sum()),
            "over_32": int((e > 32.0).sum()), "pixels": int(e.size)}


def compare(scene_path, width, height, bounces, modes, variant, rtlab, pipeline, out_dir,
            spheres="ellipsoids", peer_images=None):
    """Rows for one scene. rtlab None: only the peer's images are written (no reference);
    peer_images: a folder of <scene>-peer-<mode>.exr rendered elsewhere (say on the GPU) to
    compare instead of rendering here."""
    rows = []
    name = os.path.splitext(os.path.basename(scene_path))[0]
    try:
        sc = Scene(scene_path)
        st = sc.settings(width, height, bounces)
    except NotConverted as e:
        return [{"scene": name, "not_converted": str(e)}]
    W, H, B = st["width"], st["height"], st["bounces"]
    ref = None
    if rtlab:
        ref_path = os.path.join(out_dir, f"{name}-rtlab-{pipeline}.exr")
        run = subprocess.run([rtlab, "render", scene_path, "--pipeline", pipeline, "--size",
                              f"{W}x{H}", "--bounces", str(B), "-o", ref_path],
                             capture_output=True, text=True)
        if run.returncode != 0:
            last = (run.stderr.strip().splitlines() or [""])[-1]
            return [{"scene": name, "error": "rtlab: " + last}]
        ref = read_exr(ref_path)
    cv = None
    half = rtlab is None and not peer_images  # images to carry home: 16-bit EXR is enough
    for mode in modes:
        row = {"scene": name, "mode": mode, "variant": variant, "reference": pipeline,
               "width": W, "height": H, "bounces": B}
        if peer_images:
            path = os.path.join(peer_images, f"{name}-peer-{mode}.exr")
            if not os.path.exists(path):
                rows.append(dict(row, error=f"{path}: no such image"))
                continue
            img = read_exr(path)
            row["variant"] = f"images from {peer_images}"
        else:
            if cv is None:
                cv = whitted.Converted(sc, spheres)
            whitted.set_mode(mode)
            L, rays = whitted.render(cv, W, H, B, count_rays=True)
            whitted.dr.eval(L, rays)
            img = whitted.to_numpy(L, W, H)
            whitted.write_image(img, os.path.join(out_dir, f"{name}-peer-{mode}.exr"), half)
            row.update(rays={"traced": int(rays[0][0]), "shadow": int(rays[1][0])},
                       spheres=cv.representation["spheres"])
        if ref is not None:
            row.update(errors(img, ref))
        rows.append(row)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--size", help="WxH [scene default]")
    ap.add_argument("--bounces", type=int)
    ap.add_argument("--modes", default="symbolic")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--spheres", default="ellipsoids", choices=whitted.SPHERES)
    ap.add_argument("--rtlab")
    ap.add_argument("--pipeline", default="cpu")
    ap.add_argument("--out", help="folder for the images [a temporary one]")
    ap.add_argument("--json", help="write the rows here too (one JSON object a line)")
    ap.add_argument("--no-reference", action="store_true",
                    help="only write the peer's images into --out (a host without rtlab)")
    ap.add_argument("--peer-images", help="compare these <scene>-peer-<mode>.exr (rendered "
                    "elsewhere) instead of rendering")
    ap.add_argument("--min-within", type=float, default=0.0,
                    help="fail when a row's share within 2/255 is below this")
    a = ap.parse_args(argv)
    rtlab = None if a.no_reference else find_rtlab(a.rtlab)
    whitted.setup("scalar_rgb" if a.peer_images else a.variant)
    W = H = None
    if a.size:
        W, H = (int(v) for v in a.size.lower().split("x"))
    out = a.out or tempfile.mkdtemp(prefix="peer-compare-")
    os.makedirs(out, exist_ok=True)
    bad = 0
    lines = []
    for s in a.scenes:
        for row in compare(s, W, H, a.bounces, a.modes.split(","), a.variant, rtlab,
                           a.pipeline, out, a.spheres, a.peer_images):
            line = json.dumps(row)
            print(line, flush=True)
            lines.append(line)
            if "within_2" in row and row["within_2"] < a.min_within:
                bad += 1
            if "error" in row:
                bad += 1
    if a.json:
        with open(a.json, "a") as f:
            f.write("".join(l + "\n" for l in lines))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
