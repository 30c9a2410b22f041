#!/usr/bin/python3
"""Draws the five result charts of a sweep from the JSON that `rtlab sweep` writes.

Usage: /usr/bin/python3 scripts/charts.py results/<device-slug>/<sweep>.json [--out DIR]

Writes, next to the JSON unless --out says otherwise:
  time-vs-resolution.png   device ms per frame against megapixels     (group [resolution])
  time-vs-bounces.png      device ms per frame against the bounce limit (group [bounces])
  memory-vs-bounces.png    global and private memory against the bounce limit ([bounces])
  kernel-breakdown.png     device ms per kernel, stacked, per bounce limit ([bounces])
  speed-vs-accuracy.png    device ms against RMSE from the converged reference, with the
                           Pareto front marked ([accuracy])
A chart whose group the sweep lacks is still written, saying so, so that a result set always has
all five. Every chart's footer names the device, driver, commit and timing settings.
Needs Debian's python3-matplotlib (scripts/setup), hence /usr/bin/python3.
"""
import argparse
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

COLORS = {"mega": "#1f77b4", "wave": "#d62728"}
NAMES = {"mega": "megakernel", "wave": "wavefront"}
KERNEL_COLORS = {"megakernel": "#1f77b4", "centers": "#6baed6", "edges": "#08519c",
                 "trace": "#d62728", "image": "#ff9896", "reset": "#7f7f7f"}


def load(path):
    with open(path) as f:
        data = json.load(f)
    rows = [r for r in data["rows"] if r.get("status") == "ok"]
    return data["meta"], rows


def in_group(rows, group):
    return [r for r in rows if group in r.get("groups", [])]


def scenes_of(rows):
    out = []
    for r in rows:
        if r["scene"] not in out:
            out.append(r["scene"])
    return out


def footer(fig, meta):
    s = meta.get("settings", {})
    text = (f"{meta.get('device')} | {meta.get('platform')}, driver {meta.get('driver')} | "
            f"commit {meta.get('commit')} | sweep {meta.get('sweep')}\ndevice time = sum of the "
            f"frame's kernels by OpenCL profiling events, median of {s.get('repeats')} frames "
            f"after {s.get('warmup')} warm-up")
    fig.text(0.5, 0.005, text, ha="center", va="bottom", fontsize=7, color="#555555")


def grid(n):
    cols = min(3, max(1, n))
    rows = max(1, math.ceil(n / cols))
    # At least 9 inches wide, so that the two-line title and the footer fit one panel too.
    fig, axes = plt.subplots(rows, cols, figsize=(max(4.6 * cols, 9), 3.6 * rows + 1.0),
                             squeeze=False)
    flat = [a for row in axes for a in row]
    for a in flat[n:]:
        a.set_visible(False)
    return fig, flat


def empty_chart(path, meta, title, why):
    fig, ax = plt.subplots(figsize=(7, 3))
    ax.axis("off")
    ax.text(0.5, 0.5, f"{title}\n\n{why}", ha="center", va="center", fontsize=11)
    footer(fig, meta)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def save(fig, meta, path, title):
    fig.suptitle(title, fontsize=12)
    footer(fig, meta)
    fig.tight_layout(rect=(0, 0.05, 1, 0.93 - 0.03 * title.count("\n")))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def series(rows, key):
    """Groups rows by `key(row)` into {label: sorted rows}."""
    out = {}
    for r in rows:
        out.setdefault(key(r), []).append(r)
    return out


def setting_label(r, vary):
    parts = []
    if "size" in vary:
        parts.append(f"{r['width']}x{r['height']}")
    if "bounces" in vary:
        parts.append(f"B={r['bounces']}")
    if "shadow_samples" in vary:
        parts.append(f"s={r['shadow_samples']}")
    if "aa" in vary:
        parts.append(f"aa={r['aa']}")
    if "accel" in vary:
        parts.append(r["accel"])
    return " ".join(parts)


def varying(rows, keys):
    """Which of the keys take more than one value among rows (other than the chart's axis)."""
    out = []
    for k in keys:
        vals = {(r["width"], r["height"]) if k == "size" else r[k] for r in rows}
        if len(vals) > 1:
            out.append(k)
    return out


def line_chart(path, meta, rows, title, xkey, xlabel, ylabel, yvalue, logx, logy, other):
    scenes = scenes_of(rows)
    fig, axes = grid(len(scenes))
    for ax, scene in zip(axes, scenes):
        srows = [r for r in rows if r["scene"] == scene]
        vary = varying(srows, other)
        for (pipe, label), pts in sorted(series(srows, lambda r: (r["pipeline"], setting_label(r, vary))).items()):
            pts.sort(key=xkey)
            ax.plot([xkey(r) for r in pts], [yvalue(r) for r in pts], marker="o", ms=4,
                    color=COLORS.get(pipe), linestyle="-" if pipe == "mega" else "--",
                    label=f"{NAMES.get(pipe, pipe)} {label}".strip())
        ax.set_title(scene)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if logx:
            ax.set_xscale("log")
        else:
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        if logy:
            ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    save(fig, meta, path, title)


def time_vs_resolution(meta, rows, out):
    path = os.path.join(out, "time-vs-resolution.png")
    rows = in_group(rows, "resolution")
    title = "Frame time against resolution"
    if not rows:
        return empty_chart(path, meta, title, "this sweep has no [resolution] group")
    line_chart(path, meta, rows, title, lambda r: r["width"] * r["height"] / 1e6,
               "megapixels", "device ms per frame", lambda r: r["device_ms"], True, True,
               ["bounces", "shadow_samples", "aa", "accel"])


def time_vs_bounces(meta, rows, out):
    path = os.path.join(out, "time-vs-bounces.png")
    rows = in_group(rows, "bounces")
    title = "Frame time against bounce limit"
    if not rows:
        return empty_chart(path, meta, title, "this sweep has no [bounces] group")
    line_chart(path, meta, rows, title, lambda r: r["bounces"], "bounce limit B",
               "device ms per frame", lambda r: r["device_ms"], False, True,
               ["size", "shadow_samples", "aa", "accel"])


def memory_vs_bounces(meta, rows, out):
    path = os.path.join(out, "memory-vs-bounces.png")
    rows = in_group(rows, "bounces")
    title = "Device memory against bounce limit"
    if not rows:
        return empty_chart(path, meta, title, "this sweep has no [bounces] group")
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6))
    scenes = scenes_of(rows)
    cmap = plt.get_cmap("tab10")
    for i, scene in enumerate(scenes):
        for pipe in ("mega", "wave"):
            pts = sorted((r for r in rows if r["scene"] == scene and r["pipeline"] == pipe),
                         key=lambda r: r["bounces"])
            if not pts:
                continue
            style = dict(color=cmap(i % 10), marker="o", ms=3,
                         linestyle="-" if pipe == "mega" else "--")
            left.plot([r["bounces"] for r in pts], [r["device_bytes"] / 2**20 for r in pts],
                      label=f"{scene} {NAMES[pipe]}", **style)
            right.plot([r["bounces"] for r in pts], [r["private_bytes"] / 1024 for r in pts],
                       label=f"{scene} {NAMES[pipe]}", **style)
    sizes = sorted({f"{r['width']}x{r['height']}" for r in rows})
    left.set_title(f"global memory allocated per frame ({', '.join(sizes)})")
    left.set_ylabel("MiB")
    right.set_title("private ray storage per work-item")
    right.set_ylabel("KiB")
    for ax in (left, right):
        ax.set_xlabel("bounce limit B")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    left.legend(fontsize=7, ncol=2)
    save(fig, meta, path, title + " (solid: megakernel, dashed: wavefront)")


def kernel_breakdown(meta, rows, out):
    path = os.path.join(out, "kernel-breakdown.png")
    title = "Device time per kernel"
    chosen = in_group(rows, "bounces")
    xkey, xlabel = (lambda r: r["bounces"]), "bounce limit B (left bar megakernel, right wavefront)"
    if not chosen:
        chosen = in_group(rows, "resolution")
        xkey, xlabel = (lambda r: r["width"] * r["height"]), "pixels"
    if not chosen:
        return empty_chart(path, meta, title, "this sweep has no [bounces] or [resolution] group")
    scenes = scenes_of(chosen)
    fig, axes = grid(len(scenes))
    seen = set()
    for ax, scene in zip(axes, scenes):
        srows = [r for r in chosen if r["scene"] == scene]
        xs = sorted({xkey(r) for r in srows})
        for offset, pipe in ((-0.2, "mega"), (0.2, "wave")):
            for i, x in enumerate(xs):
                match = [r for r in srows if r["pipeline"] == pipe and xkey(r) == x]
                if not match:
                    continue
                bottom = 0.0
                for name, ms in match[0].get("kernel_ms", {}).items():
                    label = name if name not in seen else None
                    seen.add(name)
                    ax.bar(i + offset, ms, 0.38, bottom=bottom, color=KERNEL_COLORS.get(name),
                           label=label, edgecolor="white", linewidth=0.4)
                    bottom += ms
        ax.set_xticks(range(len(xs)))
        ax.set_xticklabels([str(x) for x in xs], fontsize=8)
        ax.set_title(scene)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel("device ms per frame")
        ax.grid(True, axis="y", alpha=0.3)
    handles, labels = [], []
    for ax in axes:
        for h, l in zip(*ax.get_legend_handles_labels()):
            if l not in labels:
                handles.append(h)
                labels.append(l)
    axes[0].legend(handles, labels, loc="upper left", fontsize=7)
    save(fig, meta, path, title)


def pareto(points):
    """Points (time, error, row) not beaten on both axes, by increasing time."""
    front, best = [], float("inf")
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def speed_vs_accuracy(meta, rows, out):
    path = os.path.join(out, "speed-vs-accuracy.png")
    rows = [r for r in in_group(rows, "accuracy") if "rmse" in r]
    title = "Speed against accuracy (error from the converged CPU reference)"
    if not rows:
        return empty_chart(path, meta, title, "this sweep has no scored [accuracy] group")
    ref = rows[0].get("reference", {})
    scenes = scenes_of(rows)
    fig, axes = grid(len(scenes))
    markers = {1: "o", 2: "s", 3: "^", 4: "D"}
    for ax, scene in zip(axes, scenes):
        srows = [r for r in rows if r["scene"] == scene]
        for pipe in ("mega", "wave"):
            for aa in sorted({r["aa"] for r in srows}):
                pts = [r for r in srows if r["pipeline"] == pipe and r["aa"] == aa]
                if pts:
                    ax.scatter([r["device_ms"] for r in pts], [max(r["rmse"], 1e-6) for r in pts],
                               s=[14 + 6 * math.log2(r["shadow_samples"]) for r in pts],
                               marker=markers.get(aa, "v"), color=COLORS[pipe], alpha=0.55,
                               label=f"{NAMES[pipe]} aa={aa}")
        front = pareto([(r["device_ms"], max(r["rmse"], 1e-6), r) for r in srows])
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="black",
                linewidth=1.2, label="Pareto front")
        ax.scatter([p[0] for p in front], [p[1] for p in front], s=70, facecolors="none",
                   edgecolors="black", linewidths=1.0)
        # Label the front's steps that matter: at least 3% less error than the last label
        # (a deeper bounce limit on a scene that has nothing left to bounce off gains ~0).
        last = None
        for n, (t, e, r) in enumerate(front):
            if last is not None and e > 0.97 * last and n != len(front) - 1:
                continue
            last = e
            ax.annotate(f"{r['pipeline'][0]} B{r['bounces']} s{r['shadow_samples']} aa{r['aa']}",
                        (t, e), textcoords="offset points", xytext=(4, 4), fontsize=6)
        size = f"{srows[0]['width']}x{srows[0]['height']}"
        ax.set_title(f"{scene} ({size})")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("device ms per frame")
        ax.set_ylabel("RMSE (linear, clamped to [0,1])")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6)
    sub = (f"reference: CPU double, B={ref.get('bounces')}, {ref.get('shadow_samples')} shadow "
           f"samples, aa={ref.get('aa')}; marker size grows with shadow samples\nlabels: "
           f"m/w megakernel/wavefront, B bounce limit, s shadow samples, aa N (NxN samples)")
    save(fig, meta, path, title + "\n" + sub)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json")
    ap.add_argument("--out", help="output folder [the JSON's folder]")
    args = ap.parse_args()
    meta, rows = load(args.json)
    out = args.out or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out, exist_ok=True)
    for chart in (time_vs_resolution, time_vs_bounces, memory_vs_bounces, kernel_breakdown,
                  speed_vs_accuracy):
        chart(meta, rows, out)
    print(f"charts: wrote 5 PNGs to {out}")


if __name__ == "__main__":
    sys.exit(main())
