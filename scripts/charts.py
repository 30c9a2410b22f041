#!/usr/bin/python3
"""Draws the result charts of a sweep from the JSON that `rtlab sweep` writes.

Usage: /usr/bin/python3 scripts/charts.py results/<device-slug>/<sweep>.json [--out DIR]

Writes, next to the JSON unless --out says otherwise:
  time-vs-resolution.png   device ms per frame against megapixels     (group [resolution])
  time-vs-bounces.png      device ms per frame against the bounce limit (group [bounces])
  memory-vs-bounces.png    global and private memory against the bounce limit ([bounces])
  kernel-breakdown.png     device ms per kernel, stacked, per bounce limit ([bounces])
  speed-vs-accuracy.png    device ms against RMSE from the converged reference, with the
                           Pareto front marked ([accuracy])
  limits.png               how far each pipeline goes: device time, memory and the longest launch
                           against the bounce limit and the resolution, where the wavefront tree
                           starts to tile and where (and how) each pipeline first fails ([limits])
A chart whose group the sweep lacks is written as a placeholder saying so, unless the folder has
that chart already (from another sweep of the same device, e.g. `cpu` beside `limits`), so that a
result set always has the five and a second sweep never blanks the first one's charts.
Every chart's footer names the device, driver, commit and timing settings.
Needs Debian's python3-matplotlib (scripts/setup), hence /usr/bin/python3.
"""
import argparse
import importlib.util
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import LogFormatter, MaxNLocator, NullLocator  # noqa: E402

COLORS = {"mega": "#1f77b4", "wave": "#d62728", "queue": "#2ca02c"}
NAMES = {"mega": "megakernel", "wave": "wavefront", "queue": "queue wavefront"}
KERNEL_COLORS = {"megakernel": "#1f77b4", "centers": "#6baed6", "edges": "#08519c",
                 "trace": "#d62728", "image": "#ff9896", "reset": "#7f7f7f"}


def load(path, every=False):
    with open(path) as f:
        data = json.load(f)
    rows = [r for r in data["rows"] if every or r.get("status") == "ok"]
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
    if os.path.exists(path):
        print(f"charts: kept {os.path.basename(path)} ({why})")
        return
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

def readme_module():
    """scripts/results-readme.py (standard library only): the limits analysis both scripts share."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results-readme.py")
    spec = importlib.util.spec_from_file_location("results_readme", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


LIMIT_STYLES = {("mega", "tree", False): dict(color="#1f77b4", linestyle="-"),
                ("mega", "weighted", False): dict(color="#17becf", linestyle="-."),
                ("wave", "tree", False): dict(color="#d62728", linestyle="--"),
                ("wave", "tree", True): dict(color="#ff7f0e", linestyle=":"),
                ("queue", "tree", False): dict(color="#2ca02c", linestyle="-."),
                ("queue", "weighted", False): dict(color="#2ca02c", linestyle="-.")}
HOW_SHORT = {"private tree": "private tree > limit", "tree row": "tree row > budget",
             "allocation": "allocation failed", "OpenCL error": "OpenCL error",
             "time cap": "frame > time cap", "other": "error", "skipped": "not run"}


def limits_chart(meta, all_rows, out):
    """Per scene: columns bounce limit and resolution; rows device time, global memory and the
    longest launch. Filled circles ran, squares ran with the wavefront tree in row tiles (K
    printed beside), a cross at the top marks each series' first failure (or where it was not
    run because a frame took longer than max-frame-s), with the kind."""
    rr = readme_module()
    series = rr.limit_series(all_rows)
    path = os.path.join(out, "limits.png")
    if not series:
        return
    scenes = []
    for s in series:
        if s["scene"] not in scenes:
            scenes.append(s["scene"])
    axes_kinds = [k for k in ("bounces", "size") if any(s["axis"] == k for s in series)]
    ncol = len(axes_kinds) * len(scenes)
    fig, grid_axes = plt.subplots(3, ncol, figsize=(6.4 * ncol, 11.5), squeeze=False)
    limit_rows = in_group(all_rows, "limits")
    target = next((r.get("max_launch_ms") for r in limit_rows if r.get("max_launch_ms")), 0)
    budgets = sorted({r.get("memory_budget") for r in limit_rows if r.get("memory_budget")})
    col = 0
    for scene in scenes:
        for kind in axes_kinds:
            t_ax, m_ax, l_ax = (grid_axes[i][col] for i in range(3))
            col += 1
            group = [s for s in series if s["scene"] == scene and s["axis"] == kind]
            if kind == "bounces":
                x = lambda r: r["bounces"]  # noqa: E731
                fixed = sorted({s["fixed"] for s in group})
                t_ax.set_title(f"{scene}: bounce limit up ({', '.join(f[3:] for f in fixed)})")
            else:
                x = lambda r: r["width"] * r["height"] / 1e6  # noqa: E731
                fixed = sorted({s["fixed"] for s in group})
                t_ax.set_title(f"{scene}: resolution up ({', '.join(f[3:] for f in fixed)})")
            stops = []
            for s in group:
                style = LIMIT_STYLES.get((s["pipeline"], s["layout"], bool(s["budget"])),
                                         dict(color="#7f7f7f", linestyle="-"))
                ran = s["ran"]
                tiled = [r for r in ran if rr.memory_tiles(r) > 1]
                plain = [r for r in ran if rr.memory_tiles(r) <= 1]
                for ax, val in ((t_ax, lambda r: r["device_ms"]),
                                (m_ax, lambda r: r.get("device_bytes", 0) / 2**20),
                                (l_ax, lambda r: r.get("longest_launch_ms") or float("nan"))):
                    ax.plot([x(r) for r in ran], [val(r) for r in ran], linewidth=1.4,
                            label=s["label"] if ax is t_ax else None, **style)
                    ax.plot([x(r) for r in plain], [val(r) for r in plain], "o", ms=4.5,
                            color=style["color"])
                    ax.plot([x(r) for r in tiled], [val(r) for r in tiled], "s", ms=6,
                            color=style["color"], markeredgecolor="black", markeredgewidth=0.6)
                # K tiles beside the memory points (the first, then every other one).
                for i, r in enumerate(tiled):
                    if i == 0 or i == len(tiled) - 1 or i % 2 == 0:
                        m_ax.annotate(f"{rr.memory_tiles(r)}", (x(r), r["device_bytes"] / 2**20),
                                      textcoords="offset points", xytext=(4, -9), fontsize=6.5,
                                      color=style["color"])
                if s["stop"] is not None:
                    stops.append((x(s["stop"]), s, style))
            # First failures: a dotted line through all three panels, a cross and the kind on top.
            stops.sort(key=lambda t: t[0])
            for n, (sx, s, style) in enumerate(stops):
                for ax in (t_ax, m_ax, l_ax):
                    ax.axvline(sx, color=style["color"], linestyle=":", linewidth=1.0, alpha=0.8)
                ypos = 0.96 - 0.085 * n
                t_ax.plot([sx], [ypos], marker="X", ms=9, color=style["color"],
                          markeredgecolor="black", markeredgewidth=0.6,
                          transform=t_ax.get_xaxis_transform(), clip_on=False)
                where = f"B={s['stop']['bounces']}" if kind == "bounces" else \
                    f"{s['stop']['width']}×{s['stop']['height']}"
                t_ax.text(sx, ypos, f"{where}: {HOW_SHORT.get(s['how'], s['how'])}   ",
                          transform=t_ax.get_xaxis_transform(), fontsize=7, va="center",
                          ha="right", color=style["color"],
                          bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
            # Where the device (or the budget) stops one wavefront tree buffer.
            alloc = meta.get("max_alloc_bytes")
            if alloc:
                m_ax.axhline(alloc / 2**20, color="#555555", linewidth=0.9, linestyle="--")
                m_ax.text(0.01, alloc / 2**20, f" device max allocation {alloc / 2**30:.3g} GiB",
                          transform=m_ax.get_yaxis_transform(), fontsize=7, va="bottom",
                          color="#555555")
            for b in budgets:
                if any(s["budget"] == b for s in group):
                    m_ax.axhline(b / 2**20, color="#ff7f0e", linewidth=0.9, linestyle=":")
                    m_ax.text(0.01, b / 2**20, f" memory budget {b / 2**20:g} MiB",
                              transform=m_ax.get_yaxis_transform(), fontsize=7, va="bottom",
                              color="#b35900")
            if target:
                l_ax.axhline(target, color="#555555", linewidth=0.9, linestyle="--")
                l_ax.text(0.01, target, f" max-launch-ms {target:g}",
                          transform=l_ax.get_yaxis_transform(), fontsize=7, va="bottom",
                          color="#555555")
            t_ax.set_ylabel("device ms per frame")
            m_ax.set_ylabel("global memory allocated, MiB")
            l_ax.set_ylabel("longest single launch, ms")
            for ax in (t_ax, m_ax, l_ax):
                ax.set_yscale("log")
                ax.margins(x=0.04)
                ax.grid(True, which="both", alpha=0.25)
                if kind == "bounces":
                    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
                    ax.set_xlabel("bounce limit B")
                else:
                    ax.set_xscale("log")
                    sizes = sorted({(r["width"], r["height"]) for s in group for r in s["rows"]},
                                   key=lambda wh: wh[0] * wh[1])
                    ax.set_xticks([w * h / 1e6 for w, h in sizes])
                    ax.set_xticklabels([f"{w}×{h}" for w, h in sizes], fontsize=7, rotation=30)
                    ax.xaxis.set_minor_locator(NullLocator())
                    ax.set_xlabel("resolution")
            for ax in (t_ax, m_ax, l_ax):
                lo, hi = ax.get_ylim()
                if hi / lo < 30:  # under ~1.5 decades: label the minor ticks too
                    ax.yaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False,
                                                              minor_thresholds=(2, 0.4)))
                    ax.tick_params(axis="y", which="minor", labelsize=7)
            t_ax.legend(fontsize=7, loc="lower right")
    fig.suptitle("Limits: how far each pipeline goes\n● ran   ■ ran with the wavefront "
         "tree in K row tiles (K beside the memory point)   ✕ first failure, or first setting not "
         "run after a too-long frame", fontsize=11)
    footer(fig, meta)
    fig.tight_layout(rect=(0, 0.035, 1, 0.955))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json")
    ap.add_argument("--out", help="output folder [the JSON's folder]")
    args = ap.parse_args()
    meta, all_rows = load(args.json, every=True)
    rows = [r for r in all_rows if r.get("status") == "ok"]
    out = args.out or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out, exist_ok=True)
    for chart in (time_vs_resolution, time_vs_bounces, memory_vs_bounces, kernel_breakdown,
                  speed_vs_accuracy):
        chart(meta, rows, out)
    limits_chart(meta, all_rows, out)
    print(f"charts: done in {out}")


if __name__ == "__main__":
    sys.exit(main())
