#!/usr/bin/env python3
"""Times the Mitsuba peer (whitted.py) in Dr.Jit's modes, per scene: device time from Dr.Jit's
kernel history, not Python's clock (issue 53, item 3).

For each scene and mode (symbolic = one megakernel, evaluated = a wavefront of launches): the
first frame compiles (its codegen + backend time is reported apart, as compile_ms), --warmup
frames in all run untimed, then --repeats frames each give the sum of `execution_time` over the
kernel history entries of that frame (every JIT kernel, OptiX/Embree launch, reduction and
memset); median, min and max of those. One more, untimed frame counts the rays (primary,
secondary, shadow; the counters are not in the timed kernels). Host wall time per frame (Python
tracing, launches and synchronisation included) is reported beside it as wall_ms.

One JSON object a line (appended to --out, and printed), with device, driver, commit, variant,
settings, scene, mode, the Dr.Jit flags of the mode and the sphere representation. Optionally
the last frame of each mode as PNG (--images DIR). A scene the peer does not convert gives a
row with "not_converted"; a mode that fails gives a row with "error" and the next one runs.

  timing.py scenes/cornell.json ... --variant cuda_ad_rgb --size 1920x1080 --bounces 4
            [--modes symbolic,evaluated] [--warmup 2] [--repeats 5] [--out rows.jsonl]
            [--images DIR] [--spheres ellipsoids|hybrid|shapes] [--stack local|registers]
"""
import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import whitted  # noqa: E402
from rtlab_scene import NotConverted, Scene  # noqa: E402


def commit():
    """$RTLAB_COMMIT where the caller names it (a device copy may have no .git), else git's."""
    if os.environ.get("RTLAB_COMMIT"):
        return os.environ["RTLAB_COMMIT"]
    try:
        c = subprocess.run(["git", "-C", HERE, "rev-parse", "--short=12", "HEAD"],
                           capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", HERE, "status", "--porcelain", "--", "."],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return c + ("-dirty" if dirty else "") if c else os.environ.get("RTLAB_COMMIT", "unknown")
    except (OSError, subprocess.SubprocessError):
        return os.environ.get("RTLAB_COMMIT", "unknown")


def device_info(variant):
    dr = whitted.dr
    info = {"drjit": dr.__version__, "mitsuba": whitted.mi.__version__}
    if variant.startswith("cuda"):
        try:
            q = subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version",
                                "--format=csv,noheader"], capture_output=True, text=True,
                               timeout=20).stdout.strip().splitlines()[0]
            name, driver = (x.strip() for x in q.split(","))
        except (OSError, subprocess.SubprocessError, IndexError, ValueError):
            name, driver = "unknown CUDA device", "unknown"
        info.update(device=name, driver=driver,
                    cuda=".".join(map(str, dr.detail.cuda_version())))
    else:
        name = platform.processor() or "cpu"
        try:
            with open("/proc/cpuinfo") as f:
                name = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
        except (OSError, StopIteration):
            pass
        info.update(device=f"{name} ({os.cpu_count()} threads)",
                    driver="LLVM " + ".".join(map(str, dr.detail.llvm_version())))
    return info


STACK = "local"


def frame(cv, st, count_rays=False):
    """One frame; returns (kernel history entries, wall seconds, image arrays, rays)."""
    dr = whitted.dr
    dr.kernel_history()  # clears
    t0 = time.perf_counter()
    L, rays = whitted.render(cv, st["width"], st["height"], st["bounces"],
                             count_rays=count_rays, stack=STACK)
    dr.eval(L, rays)
    dr.sync_thread()
    wall = time.perf_counter() - t0
    return dr.kernel_history(), wall, L, rays


def kernel_ms(hist):
    return sum(float(k.get("execution_time", 0.0)) for k in hist)


def compile_ms(hist):
    return sum(float(k.get("codegen_time", 0.0)) + float(k.get("backend_time", 0.0))
               for k in hist)


def time_scene(path, a, base, out):
    name = os.path.splitext(os.path.basename(path))[0]
    W = H = None
    if a.size:
        W, H = (int(v) for v in a.size.lower().split("x"))
    try:
        sc = Scene(path)
        st = sc.settings(W, H, a.bounces)
    except NotConverted as e:
        return [dict(base, scene=name, not_converted=str(e))]
    t0 = time.perf_counter()
    cv = whitted.Converted(sc, a.spheres)
    whitted.dr.eval()
    whitted.dr.sync_thread()
    convert_s = time.perf_counter() - t0
    rows = []
    for mode in a.modes.split(","):
        row = dict(base, scene=name, mode=mode, width=st["width"], height=st["height"],
                   bounces=st["bounces"], shadow_samples=st["shadow_samples"],
                   objects=sc.counts(), representation=cv.representation,
                   convert_s=round(convert_s, 3))
        try:
            whitted.set_mode(mode)
            dr = whitted.dr
            row["flags"] = {f: bool(dr.flag(getattr(dr.JitFlag, f))) for f in
                            ("SymbolicLoops", "SymbolicCalls", "CompressLoops")}
            dr.set_flag(dr.JitFlag.KernelHistory, True)
            first, wall_first, _, _ = frame(cv, st)
            row["first_frame_ms"] = round(kernel_ms(first), 4)
            row["compile_ms"] = round(compile_ms(first), 3)
            row["first_wall_ms"] = round(wall_first * 1e3, 3)
            row["first_kernels"] = {"launches": len(first),
                                    "cache_hits": sum(1 for k in first if k.get("cache_hit")),
                                    "from_disk": sum(1 for k in first if k.get("cache_disk"))}
            for _ in range(max(0, a.warmup - 1)):
                frame(cv, st)
            times, walls, launches, recompiled = [], [], [], 0
            for _ in range(a.repeats):
                hist, wall, L, _ = frame(cv, st)
                times.append(kernel_ms(hist))
                walls.append(wall * 1e3)
                launches.append(len(hist))
                recompiled += sum(1 for k in hist if "cache_hit" in k and not k["cache_hit"])
            row.update(median_ms=round(statistics.median(times), 4), min_ms=round(min(times), 4),
                       max_ms=round(max(times), 4), times_ms=[round(t, 4) for t in times],
                       wall_median_ms=round(statistics.median(walls), 3),
                       launches=int(statistics.median(launches)),
                       recompiled_in_repeats=recompiled)
            if a.images:
                img = whitted.to_numpy(L, st["width"], st["height"])
                whitted.write_image(img, os.path.join(a.images, f"{name}-{mode}.png"))
            dr.set_flag(dr.JitFlag.KernelHistory, False)
            _, _, _, rays = frame(cv, st, count_rays=True)
            traced, shadow = (int(x[0]) for x in rays)
            primary = st["width"] * st["height"]
            row["rays"] = {"primary": primary, "secondary": traced - primary, "shadow": shadow,
                           "total": traced + shadow}
            row["mrays_per_s"] = round((traced + shadow) / (row["median_ms"] * 1e3), 2) \
                if row["median_ms"] > 0 else None
        except Exception as e:  # one failing mode does not end the scene
            first_line = str(e).strip().splitlines()[0] if str(e).strip() else ""
            row["error"] = f"{type(e).__name__}: {first_line}"
            traceback.print_exc(file=sys.stderr)
        finally:
            whitted.dr.set_flag(whitted.dr.JitFlag.KernelHistory, False)
        print(json.dumps(row), flush=True)
        if out:
            with open(out, "a") as f:
                f.write(json.dumps(row) + "\n")
        rows.append(row)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--size", help="WxH [scene default]")
    ap.add_argument("--bounces", type=int)
    ap.add_argument("--modes", default="symbolic,evaluated")
    ap.add_argument("--warmup", type=int, default=2, help="untimed frames, the first included")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--spheres", default="ellipsoids", choices=whitted.SPHERES)
    ap.add_argument("--stack", default="local", choices=whitted.STACKS,
                    help="the per-lane stack: local memory or loop variables [local]")
    ap.add_argument("--out", help="append the rows here (one JSON object a line)")
    ap.add_argument("--images", help="folder for the last frame of each scene and mode (PNG)")
    a = ap.parse_args(argv)
    global STACK
    STACK = a.stack
    whitted.setup(a.variant)
    if a.images:
        os.makedirs(a.images, exist_ok=True)
    base = {"peer": "mitsuba", "variant": a.variant, "commit": commit(),
            **device_info(a.variant), "warmup": a.warmup, "repeats": a.repeats,
            "spheres": a.spheres, "stack": a.stack}
    for s in a.scenes:
        r = time_scene(s, a, base, a.out)
        if len(r) == 1 and "not_converted" in r[0]:
            print(json.dumps(r[0]), flush=True)
            if a.out:
                with open(a.out, "a") as f:
                    f.write(json.dumps(r[0]) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
