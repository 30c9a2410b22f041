#!/usr/bin/python3
"""Draws the result charts of a sweep from the JSON that `rtlab sweep` writes.

Usage: /usr/bin/python3 scripts/charts.py results/<device-slug>/<sweep>.json [--out DIR]

Writes, next to the JSON unless --out says otherwise, each chart whose group the sweep has:
  time-vs-resolution.png   device ms per frame against resolution      (group [resolution])
  time-vs-bounces.png      device ms per frame against the bounce limit (group [bounces])
  memory-vs-bounces.png    global and private memory against the bounce limit ([bounces])
  kernel-breakdown.png     each kernel's share of the frame, and the frame's ms ([bounces])
  speed-vs-accuracy.png    device ms against RMSE from the converged reference, with the
                           Pareto front marked ([accuracy], scored cells only)
  limits.png               how far each pipeline goes (charts_limits.py, [limits])
  crossover.png            time over the best megakernel against material cost, a panel per
                           number of materials (charts_crossover.py, [crossover])
A chart whose group the sweep lacks is not written (and one already in the folder, from another
sweep of the same device, is left alone). The pipelines, their titles, colours and layouts come
from the rows (sweep_rows.py). Every chart's footer names the device, driver, commit and timing.
Needs Debian's python3-matplotlib (scripts/setup), hence /usr/bin/python3.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from chart_style import (DPI, MARKERS, figure, legend_height, legend_row, log_ticks,  # noqa: E402
                         place_labels, plt, point_boxes, resolution_axis)
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from sweep_rows import PALETTE, Series, failure, in_group  # noqa: E402

KERNEL_COLORS = {"megakernel": "#1f77b4", "centers": "#6baed6", "edges": "#08519c",
                 "trace": "#d62728", "image": "#ff9896", "reset": "#7f7f7f"}
MERGE = 0.05  # lines closer than this (relative) are one line on a log axis of several decades
SETTING_KEYS = ("size", "bounces", "shadow_samples", "aa", "accel")


def load(path):
    """(meta, rows) of a sweep JSON, or None when the file is not one."""
    try:
        with open(path) as f:
            data = json.load(f)
        return data["meta"], data["rows"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def scenes_of(rows):
    return list(dict.fromkeys(r["scene"] for r in rows))


def value(r, k):
    return (r["width"], r["height"]) if k == "size" else r[k]


def setting_text(r, keys):
    """'1280×720 B=4 s=1 aa=1 bvh' for the keys given."""
    names = {"size": lambda r: f"{r['width']}×{r['height']}",
             "bounces": lambda r: f"B={r['bounces']}",
             "shadow_samples": lambda r: f"s={r['shadow_samples']}",
             "aa": lambda r: f"aa={r['aa']}",
             "accel": lambda r: "" if r["accel"] in ("-", "none") else r["accel"]}
    return " ".join(t for t in (names[k](r) for k in keys) if t)


def varying(rows, keys):
    """Which of the keys take more than one value among rows."""
    return [k for k in keys if len({value(r, k) for r in rows}) > 1]


def line_chart(meta, rows, title, axis_key, ylabel):
    """Device ms against the bounce limit or the resolution, a panel per scene; the settings a
    scene keeps fixed are in its title, those that vary get a marker each."""
    scenes, series = scenes_of(rows), Series(rows)
    fig, panels, legend_ax = figure(meta, title, len(scenes))
    other = [k for k in SETTING_KEYS if k != axis_key]
    handles, labels = [], []
    for ax, scene in zip(panels, scenes):
        srows = [r for r in rows if r["scene"] == scene]
        vary = varying(srows, other)
        variants = sorted({setting_text(r, vary) for r in srows})
        for key in series.keys:
            for n, variant in enumerate(variants):
                pts = sorted((r for r in srows if series.key(r) == key and
                              setting_text(r, vary) == variant),
                             key=lambda r: value(r, axis_key) if axis_key != "size"
                             else r["width"] * r["height"])
                if not pts:
                    continue
                xs = [r["bounces"] if axis_key == "bounces" else r["width"] * r["height"] / 1e6
                      for r in pts]
                label = f"{series.label(key)} {variant}".strip()
                line, = ax.plot(xs, [r["device_ms"] for r in pts], marker=MARKERS[n % 10], ms=4,
                                color=series.color(key), linestyle=series.linestyle(key),
                                label=label)
                handles.append(line)
                labels.append(label)
        fixed = setting_text(srows[0], [k for k in other if k not in vary])
        ax.set_title(f"{scene}" + (f" ({fixed})" if fixed else ""), fontsize=9)
        ax.set_ylabel(ylabel)
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        if axis_key == "size":
            resolution_axis(ax, srows)
        else:
            ax.set_xlabel("bounce limit B")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        log_ticks(ax)
    legend_row(legend_ax, handles, labels)
    return fig


def time_vs_resolution(meta, rows):
    rows = in_group(rows, "resolution")
    return rows and line_chart(meta, rows, "Frame time against resolution (log-log)",
                               "size", "device ms per frame")


def time_vs_bounces(meta, rows):
    rows = in_group(rows, "bounces")
    return rows and line_chart(meta, rows, "Frame time against bounce limit", "bounces",
                               "device ms per frame")


def scene_list(names, every):
    rest = [s for s in every if s not in names]
    if not rest:
        return "every scene"
    if len(rest) <= 2 and len(names) > len(rest):
        return f"every scene but {', '.join(rest)}"
    return ", ".join(names)


def curves(rows, series, y):
    """Lines of y against the bounce limit, one per (series, scene), merged where they coincide
    (within MERGE at every point: one line on a log axis) so that a legend entry is a line seen."""
    out = []  # [xs, ys, [series keys], [scenes]]
    for key in series.keys:
        for scene in scenes_of(rows):
            pts = sorted((r for r in rows if r["scene"] == scene and series.key(r) == key),
                         key=lambda r: r["bounces"])
            if not pts:
                continue
            xs, ys = [r["bounces"] for r in pts], [y(r) for r in pts]
            same = next((c for c in out if c[0] == xs and all(
                abs(a - b) <= MERGE * max(abs(a), abs(b), 1e-12) for a, b in zip(c[1], ys))), None)
            if same:
                same[2] += [key] if key not in same[2] else []
                same[3] += [scene] if scene not in same[3] else []
            else:
                out.append([xs, ys, [key], [scene]])
    return out


def memory_vs_bounces(meta, rows):
    rows = in_group(rows, "bounces")
    if not rows:
        return None
    series, every = Series(rows), scenes_of(rows)
    sizes = sorted({f"{r['width']}×{r['height']}" for r in rows})
    panels = [("global memory allocated per frame", "MiB", lambda r: r["device_bytes"] / 2**20),
              ("private ray storage per work-item", "KiB", lambda r: r["private_bytes"] / 1024)]
    lines = [curves(rows, series, y) for _, _, y in panels]
    fig, axes, legend_ax = figure(
        meta, f"Device memory against bounce limit ({', '.join(sizes)})", 2, cols=2,
        panel=(6, 3.8), legend_rows=1 + 0.5 * max(len(c) for c in lines))
    legends = []
    for ax, (what, unit, _), found in zip(axes, panels, lines):
        handles = []
        for n, (xs, ys, keys, scenes) in enumerate(found):
            color = series.color(keys[0]) if len(keys) == 1 else "#333333"
            style = series.linestyle(keys[0]) if len(keys) == 1 else "-"
            label = f"{', '.join(series.label(k) for k in keys)}: {scene_list(scenes, every)}"
            handles += ax.plot(xs, ys, color=color, linestyle=style, marker=MARKERS[n % 10],
                               ms=3.5, label=label)
        ax.set_title(what, fontsize=9)
        ax.set_ylabel(unit)
        ax.set_xlabel("bounce limit B")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        log_ticks(ax)
        legends.append(legend_ax.legend(handles=handles, loc="upper center",
                                        bbox_to_anchor=(0.25 if ax is axes[0] else 0.75, 1.0),
                                        fontsize=7.5, frameon=False, title_fontsize=7.5,
                                        title=f"{what} (lines within {MERGE:.0%} merged)"))
    legend_ax.add_artist(legends[0])
    return fig


# Colours for kernels without one of their own: matplotlib's tab20 less the hues KERNEL_COLORS
# holds, so that no two kernels of a chart share a colour (a queue frame has about a dozen).
OTHER_KERNEL_COLORS = [c for c in
                       ["#2ca02c", "#98df8a", "#ff7f0e", "#ffbb78", "#9467bd", "#c5b0d5",
                        "#8c564b", "#c49c94", "#e377c2", "#f7b6d2", "#bcbd22", "#dbdb8d",
                        "#17becf", "#9edae5", "#393b79", "#637939", "#8c6d31", "#843c39",
                        "#7b4173", "#5254a3"]
                       if c not in KERNEL_COLORS.values()]


def kernel_colors(names):
    unknown = sorted(n for n in names if n not in KERNEL_COLORS)
    return {**{n: OTHER_KERNEL_COLORS[i % len(OTHER_KERNEL_COLORS)] for i, n in enumerate(unknown)},
            **KERNEL_COLORS}


def kernel_breakdown(meta, rows):
    """Per scene: each kernel's share of the frame as stacked bars (one bar per series at each
    bounce limit), and the frame's device ms on a log axis beside, so that small B stays
    readable next to B=8."""
    chosen, axis = in_group(rows, "bounces"), "bounces"
    if not chosen:
        chosen, axis = in_group(rows, "resolution"), "size"
    chosen = [r for r in chosen if r.get("kernel_ms")]
    if not chosen:
        return None
    series, scenes = Series(chosen), scenes_of(chosen)
    colors = kernel_colors({k for r in chosen for k in r["kernel_ms"]})
    # The legend's row sized for every kernel and every series' frame-time line it will hold.
    entries = sorted(colors.keys() & {k for r in chosen for k in r["kernel_ms"]}) + \
        [f"{series.label(k)}: frame ms" for k in series.keys]
    cols = min(len(scenes), 3)
    rows_needed = legend_height(max(4.6 * cols, 9), entries, 5)
    fig, panels, legend_ax = figure(meta, "Device time per kernel: share of the frame (bars) "
                                    "and frame time (points, right axis)", len(scenes),
                                    legend_rows=rows_needed)
    width = 0.8 / len(series.keys)
    handles, labels = [], []
    for ax, scene in zip(panels, scenes):
        srows = [r for r in chosen if r["scene"] == scene]
        xkey = (lambda r: r["bounces"]) if axis == "bounces" else \
            (lambda r: r["width"] * r["height"])
        xs = sorted({xkey(r) for r in srows})
        total_ax = ax.twinx()
        for j, key in enumerate(series.keys):
            offset = (j - (len(series.keys) - 1) / 2) * width
            pts = {xkey(r): r for r in srows if series.key(r) == key}
            for i, x in enumerate(xs):
                r = pts.get(x)
                if not r:
                    continue
                total, bottom = sum(r["kernel_ms"].values()) or 1.0, 0.0
                for name, t in r["kernel_ms"].items():
                    share = 100 * t / total
                    ax.bar(i + offset, share, width * 0.95, bottom=bottom, color=colors[name],
                           edgecolor="white", linewidth=0.4)
                    bottom += share
                    if name not in labels:
                        handles.append(Patch(color=colors[name]))
                        labels.append(name)
            at = [i + offset for i, x in enumerate(xs) if x in pts]
            # Black on white: the bars behind already use the series' hues for kernels.
            line, = total_ax.plot(at, [pts[x]["device_ms"] for x in xs if x in pts],
                                  marker=MARKERS[j % len(MARKERS)], ms=4.5, color="black",
                                  markerfacecolor="white", linestyle=series.linestyle(key),
                                  linewidth=0.9)
            label = f"{series.label(key)}: frame ms"
            if label not in labels:
                handles.append(line)
                labels.append(label)
        total_ax.set_yscale("log")
        total_ax.set_ylabel("device ms per frame (log)", fontsize=8)
        log_ticks(total_ax)
        ax.set_ylim(0, 100)
        ax.set_xticks(range(len(xs)))
        first = srows[0]
        if axis == "bounces":
            ax.set_xticklabels([str(x) for x in xs], fontsize=8)
            ax.set_xlabel("bounce limit B", fontsize=8)
        else:
            sizes = {r["width"] * r["height"]: f"{r['width']}×{r['height']}" for r in srows}
            ax.set_xticklabels([sizes[x] for x in xs], fontsize=7, rotation=30)
            ax.set_xlabel("resolution", fontsize=8)
        fixed = [k for k in SETTING_KEYS if k != axis and k not in varying(srows, SETTING_KEYS)]
        ax.set_title(f"{scene} ({setting_text(first, fixed)})", fontsize=9)
        ax.set_ylabel("% of the frame's device time")
    order = ", ".join(series.label(k) for k in series.keys)
    legend_row(legend_ax, handles, labels, ncol=min(len(labels), 5))
    legend_ax.set_title(f"bars at each x, left to right: {order}", fontsize=8)
    return fig


def pareto(points):
    """Points (time, error, row) not beaten on both axes, by increasing time."""
    front, best = [], float("inf")
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def shared_error(rows):
    """(settings where every series' frame has the same error, settings measured on more than
    one series): equal errors mean equal images, the points differ only in time."""
    by = {}
    for r in rows:
        k = (r["scene"], r["width"], r["height"], r["bounces"], r["shadow_samples"], r["aa"])
        by.setdefault(k, []).append(r["rmse"])
    multi = [v for v in by.values() if len(v) > 1]
    return sum(1 for v in multi if max(v) == min(v)), len(multi)


def size_of(s):
    return 14 + 8 * math.log2(s)


def speed_vs_accuracy(meta, rows):
    rows = [r for r in in_group(rows, "accuracy") if r.get("rmse") is not None]
    if not rows:
        return None
    ref = rows[0].get("reference", {})
    series, scenes = Series(rows), scenes_of(rows)
    same, multi = shared_error(rows)
    note = (f"\nthe error is the same on every pipeline at {same} of the {multi} settings run on "
            "more than one (the same image): their points share a height, only the time differs"
            if multi else "")
    fig, panels, legend_ax = figure(
        meta, "Speed against accuracy (error from the converged CPU reference, log-log)\n"
        f"reference: CPU double, B={ref.get('bounces')}, {ref.get('shadow_samples')} shadow "
        f"samples, aa={ref.get('aa')}" + note, len(scenes), legend_rows=2.2)
    aas = sorted({r["aa"] for r in rows})
    shadows = sorted({r["shadow_samples"] for r in rows})
    labelled = []
    for ax, scene in zip(panels, scenes):
        srows = [r for r in rows if r["scene"] == scene]
        for key in series.keys:
            for n, aa in enumerate(aas):
                pts = [r for r in srows if series.key(r) == key and r["aa"] == aa]
                if pts:
                    ax.scatter([r["device_ms"] for r in pts], [max(r["rmse"], 1e-6) for r in pts],
                               s=[size_of(r["shadow_samples"]) for r in pts],
                               marker=MARKERS[n % 10], color=series.color(key), alpha=0.55)
        front = pareto([(r["device_ms"], max(r["rmse"], 1e-6), r) for r in srows])
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="black",
                linewidth=1.1)
        ax.scatter([p[0] for p in front], [p[1] for p in front], s=70, facecolors="none",
                   edgecolors="black", linewidths=1.0)
        ax.set_title(f"{scene} ({srows[0]['width']}×{srows[0]['height']})", fontsize=9)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("device ms per frame")
        ax.set_ylabel("RMSE (linear, clamped to [0,1])")
        ax.grid(True, which="both", alpha=0.3)
        log_ticks(ax, "x")
        log_ticks(ax)
        labelled.append((ax, front))
    handles = [Line2D([], [], linestyle="none", marker="o", color=series.color(k), alpha=0.7)
               for k in series.keys]
    labels = [series.label(k) for k in series.keys]
    handles += [Line2D([], [], linestyle="none", marker=MARKERS[n % 10], color="#777777")
                for n in range(len(aas))]
    labels += [f"aa={aa} ({aa}×{aa} samples)" for aa in aas]
    handles += [Line2D([], [], linestyle="none", marker="o", color="#777777",
                       markersize=math.sqrt(size_of(s))) for s in shadows]
    labels += [f"{s} shadow sample{'s' if s > 1 else ''}" for s in shadows]
    handles.append(Line2D([], [], color="black", marker="o", markerfacecolor="none"))
    labels.append("Pareto front (labelled: B bounce limit, s shadow samples, aa)")
    legend_row(legend_ax, handles, labels, ncol=min(len(labels), 5))
    for ax, front in labelled:
        label_front(fig, ax, front)
    return fig


def label_front(fig, ax, front):
    """Labels the front's points where there is room, the ones that cut the error most first."""
    gains = [(front[i - 1][1] / p[1] if i else float("inf"), i) for i, p in enumerate(front)]
    order = [i for _, i in sorted(gains, reverse=True)]
    boxes = point_boxes(fig, ax, [(t, e) for t, e, _ in front], 4.5)
    place_labels(fig, ax, [(front[i][0], front[i][1],
                            f"B{front[i][2]['bounces']} s{front[i][2]['shadow_samples']} "
                            f"aa{front[i][2]['aa']}", False) for i in order], avoid=boxes)


CHARTS = {"time-vs-resolution.png": time_vs_resolution, "time-vs-bounces.png": time_vs_bounces,
          "memory-vs-bounces.png": memory_vs_bounces, "kernel-breakdown.png": kernel_breakdown,
          "speed-vs-accuracy.png": speed_vs_accuracy}


def draw_all(meta, all_rows):
    """{file name: figure} for every chart the rows have data for."""
    import charts_crossover
    import charts_limits
    rows = [r for r in all_rows if failure(r) == ""]
    figs = {name: chart(meta, rows) for name, chart in CHARTS.items()}
    figs["limits.png"] = charts_limits.limits_chart(meta, all_rows)
    figs["crossover.png"] = charts_crossover.crossover_chart(meta, all_rows)
    return figs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json")
    ap.add_argument("--out", help="output folder [the JSON's folder]")
    args = ap.parse_args()
    sweep = load(args.json)
    if sweep is None:
        sys.exit(f"{ap.prog}: {args.json}: not a sweep JSON (one with \"meta\" and \"rows\")")
    meta, all_rows = sweep
    out = args.out or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out, exist_ok=True)
    for name, fig in draw_all(meta, all_rows).items():
        if not fig:
            print(f"charts: no {name} (the sweep has no cells for it)")
            continue
        fig.savefig(os.path.join(out, name), dpi=DPI)
        plt.close(fig)
    print(f"charts: done in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
