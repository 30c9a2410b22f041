#!/usr/bin/env python3
"""Reads the rounds of scripts/gpu-kernel-ab (ab-A-<r>.json, ab-B-<r>.json: Google Benchmark
JSON of rtlab-bench) and writes a Markdown table: per benchmark, A's and B's median device ms
over every repetition of every round, the spread of each (min..max of the repetitions), and the
verdict: B slower or faster only where its median lies outside A's spread and A's outside B's;
otherwise a tie (the difference is inside the spread).

    python3 tools/rtlab_report kernel-ab DIR [--labels before,after] > table.md
"""
import argparse
import glob
import json
import os
import statistics
import sys


def reps(paths):
    """{benchmark name: [ms per frame of each repetition]} over the files, plus the context."""
    out, ctx = {}, {}
    for path in paths:
        with open(path) as f:
            d = json.load(f)
        ctx = d.get("context", ctx)
        for b in d.get("benchmarks", []):
            if b.get("run_type") != "iteration" or "error_occurred" in b:
                continue
            name = b["run_name"].split("/iterations:")[0].removeprefix("render/")
            out.setdefault(name, []).append(b["real_time"])
    return out, ctx


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir")
    ap.add_argument("--labels", default="A,B")
    a = ap.parse_args(argv)
    la, lb = a.labels.split(",")
    ra, ctx = reps(sorted(glob.glob(os.path.join(a.dir, "ab-A-*.json"))))
    rb, _ = reps(sorted(glob.glob(os.path.join(a.dir, "ab-B-*.json"))))
    if not ra or not rb:
        sys.exit(f"kernel-ab: no rounds of both A and B in {a.dir}")
    print(f"device {ctx.get('device')}, driver {ctx.get('driver')}, rtlab-bench built at "
          f"{ctx.get('rtlab_commit')}; {la} and {lb} are kernel trees or binaries, timed in "
          "alternating rounds; ms per frame by OpenCL profiling events, median over every "
          "repetition of every round; spread = min..max of those repetitions\n")
    print(f"| benchmark | {la} ms | {la} spread | {lb} ms | {lb} spread | {lb}/{la} | verdict |")
    print("|---|---:|---|---:|---|---:|---|")
    counts = {}
    for name in sorted(set(ra) & set(rb)):
        xa, xb = ra[name], rb[name]
        ma, mb = statistics.median(xa), statistics.median(xb)
        if mb > max(xa) and ma < min(xb):
            verdict = f"{lb} slower"
        elif mb < min(xa) and ma > max(xb):
            verdict = f"{lb} faster"
        else:
            verdict = "tie (inside the spread)"
        counts[verdict] = counts.get(verdict, 0) + 1
        print(f"| {name} | {ma:.3f} | {min(xa):.3f}..{max(xa):.3f} | {mb:.3f} | "
              f"{min(xb):.3f}..{max(xb):.3f} | {mb / ma:.3f} | {verdict} |")
    print("\n" + ", ".join(f"{v}: {n}" for v, n in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
