"""Draws the result charts of a sweep from the JSON that `rtlab sweep` writes.

Usage: python3 -m rtlab_report charts results/<device-slug>/<sweep>.json [--out DIR]

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
sweep of the same device, is left alone). The pipelines, their titles and layouts come from the
rows (sweep_rows.py), their colours and markers from the one palette (chart_style.py), wins and
ties from compare.py. Every chart's footer names the device, driver, commit and timing.
Needs Debian's python3-matplotlib (scripts/setup), hence /usr/bin/python3.
"""
import argparse
import json
import math
import os
import sys

from .chart_style import (DPI, LINESTYLES, MARKERS, MISSING_MARKER, figure,
                         legend_height, legend_row, log_ticks, place_labels, plt, point_boxes,
                         resolution_axis, series_style)
from .compare import (ERROR_DECIMALS, PARETO_RTOL, error_agreement, error_setting, pareto,
                      spread)
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator
from .sweep_rows import Series, failure, in_group

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
    """Device ms against the bounce limit or the resolution, a panel per scene, each point's
    frame spread as an error bar; the settings a scene keeps fixed are in its title, those that
    vary get a line style each. Every panel spans the values the chart's rows take along the
    axis (a sweep stopped by its time limit leaves later scenes shorter): a cell a series did
    not measure there breaks its line and is marked on the bottom edge, so that neither a line
    that stops nor one drawn across a gap is read as a trend."""
    scenes, series = scenes_of(rows), Series(rows)
    guess = [series.label(k) for k in series.keys] + ["× on the bottom edge: not measured (the "
                                                      "series' colour)"] * 2
    fig, panels, legend_ax = figure(meta, title, len(scenes), legend_rows=legend_height(
        max(4.6 * min(3, len(scenes)), 9), guess, 4))
    other = [k for k in SETTING_KEYS if k != axis_key]
    handles, labels, any_missing = [], [], False
    xof = (lambda r: r["bounces"]) if axis_key == "bounces" else \
        (lambda r: r["width"] * r["height"] / 1e6)
    xs = sorted({xof(r) for r in rows})
    for ax, scene in zip(panels, scenes):
        srows = [r for r in rows if r["scene"] == scene]
        vary = varying(srows, other)
        variants = sorted({setting_text(r, vary) for r in srows})
        keys = [k for k in series.keys if any(series.key(r) == k for r in srows)]
        missing = []  # (series index, [x], colour)
        for n, variant in enumerate(variants):
            vrows = [r for r in srows if setting_text(r, vary) == variant]
            for j, key in enumerate(keys):
                pts = {xof(r): r for r in vrows if series.key(r) == key}
                if not pts:
                    continue
                st = series_style(series, key)
                style = st["linestyle"] if len(variants) == 1 else LINESTYLES[n % len(LINESTYLES)]
                ys = [pts[x]["device_ms"] if x in pts else float("nan") for x in xs]
                lo = [pts[x]["device_ms"] - spread(pts[x])[0] if x in pts else 0 for x in xs]
                hi = [spread(pts[x])[1] - pts[x]["device_ms"] if x in pts else 0 for x in xs]
                label = f"{series.label(key)} {variant}".strip()
                line = ax.errorbar(xs, ys, yerr=[lo, hi], marker=st["marker"], ms=4,
                                   color=st["color"], linestyle=style, elinewidth=0.8,
                                   capsize=2, label=label)
                handles.append(line)
                labels.append(label)
                gaps = [x for x in xs if x not in pts]
                if gaps:
                    missing.append((j, gaps, st["color"]))
        fixed = setting_text(srows[0], [k for k in other if k not in vary])
        ax.set_title(f"{scene}" + (f" ({fixed})" if fixed else ""), fontsize=9)
        ax.set_ylabel(ylabel)
        ax.set_yscale("log")
        if missing:
            any_missing = True
            # A strip under the data, a row of crosses per series that missed cells there.
            rows_needed = len({j for j, _, _ in missing})
            lo, hi = ax.get_ylim()
            ax.set_ylim(lo / (hi / lo) ** (0.08 * rows_needed + 0.04), hi)
            edge = ax.get_xaxis_transform()
            for row_n, (j, gaps, color) in enumerate(sorted(missing)):
                ax.plot(gaps, [0.035 + 0.06 * row_n] * len(gaps), MISSING_MARKER,
                        transform=edge, color=color, ms=6, mew=1.6)
        ax.grid(True, which="both", alpha=0.3)
        if axis_key == "size":
            resolution_axis(ax, srows)
        else:
            ax.set_xlabel("bounce limit B")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        log_ticks(ax)
    if any_missing:
        handles.append(Line2D([], [], linestyle="none", marker=MISSING_MARKER, color="#555555",
                              mew=1.6))
        labels.append("not measured (in the series' colour, in a strip at the bottom)")
    handles.append(Line2D([], [], color="#555555", marker="|", linestyle="none", ms=8))
    labels.append("bar: fastest to slowest timed frame")
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
            color = series_style(series, keys[0])["color"] if len(keys) == 1 else "#333333"
            style = series_style(series, keys[0])["linestyle"] if len(keys) == 1 else "-"
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


# Kernel colours: a panel shows one series' kernels, each series has its own legend, so the
# colours restart for every series and the kernels of one frame are as far apart as they can be
# (a queue frame has about a dozen). Dark hues first, their light partners after.
KERNEL_PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                  "#7f7f7f", "#bcbd22", "#17becf", "#aec7e8", "#ffbb78", "#98df8a", "#ff9896",
                  "#c5b0d5", "#c49c94", "#f7b6d2", "#dbdb8d"]


def kernel_names(rows):
    """The kernels of these rows, in the order the frames ran them."""
    return list(dict.fromkeys(k for r in rows for k in r["kernel_ms"]))


def kernel_breakdown(meta, rows):
    """A panel per scene (rows of the grid) and series (columns): each kernel's share of the
    frame as a stacked bar at each bounce limit, the frame's device ms printed above its bar.
    One series a panel, so bars are wide and no second axis lies over them."""
    chosen, axis = in_group(rows, "bounces"), "bounces"
    if not chosen:
        chosen, axis = in_group(rows, "resolution"), "size"
    chosen = [r for r in chosen if r.get("kernel_ms")]
    if not chosen:
        return None
    series, scenes = Series(chosen), scenes_of(chosen)
    keys = series.keys
    names = {k: kernel_names([r for r in chosen if series.key(r) == k]) for k in keys}
    colors = {k: {n: KERNEL_PALETTE[i % len(KERNEL_PALETTE)] for i, n in enumerate(v)}
              for k, v in names.items()}
    lines = max(math.ceil(len(v) / 2) for v in names.values())
    fig, panels, legend_ax = figure(
        meta, "Device time per kernel: each kernel's share of the frame, the frame's device ms "
        "above its bar", len(scenes) * len(keys), cols=len(keys), panel=(3.6, 2.6),
        legend_rows=(0.2 * lines + 0.45) / 0.45)
    xkey = (lambda r: r["bounces"]) if axis == "bounces" else (lambda r: r["width"] * r["height"])
    any_missing = False
    for i, scene in enumerate(scenes):
        srows = [r for r in chosen if r["scene"] == scene]
        xs = sorted({xkey(r) for r in srows})
        for j, key in enumerate(keys):
            ax = panels[i * len(keys) + j]
            pts = {xkey(r): r for r in srows if series.key(r) == key}
            for n, x in enumerate(xs):
                r = pts.get(x)
                if not r:
                    any_missing = True
                    ax.plot([n], [50], MISSING_MARKER, color="#777777", ms=7, mew=1.6)
                    continue
                total, bottom = sum(r["kernel_ms"].values()) or 1.0, 0.0
                for name in names[key]:
                    share = 100 * r["kernel_ms"].get(name, 0.0) / total
                    ax.bar(n, share, 0.8, bottom=bottom, color=colors[key][name],
                           edgecolor="white", linewidth=0.3)
                    bottom += share
                ax.text(n, 102, ms_text(r["device_ms"]), ha="center", va="bottom",
                        fontsize=6, rotation=90)
            ax.set_ylim(0, 125)
            ax.set_yticks([0, 25, 50, 75, 100])
            ax.set_xlim(-0.6, len(xs) - 0.4)
            ax.set_xticks(range(len(xs)))
            if axis == "bounces":
                ax.set_xticklabels([str(x) for x in xs], fontsize=7)
                ax.set_xlabel("bounce limit B", fontsize=7)
            else:
                sizes = {r["width"] * r["height"]: f"{r['width']}×{r['height']}" for r in srows}
                ax.set_xticklabels([sizes[x] for x in xs], fontsize=6, rotation=30)
                ax.set_xlabel("resolution", fontsize=7)
            ax.tick_params(axis="y", labelsize=7)
            if j == 0:
                ax.set_ylabel("% of device time", fontsize=7)
            fixed = [k for k in SETTING_KEYS if k != axis and k not in varying(srows, SETTING_KEYS)]
            ax.set_title(f"{scene} ({setting_text(srows[0], fixed)})\n{series.label(key)}",
                         fontsize=7.5, color=series_style(series, key)["color"])
    for j, key in enumerate(keys):
        handles = [Patch(color=colors[key][n]) for n in names[key]]
        legend = legend_ax.legend(handles, names[key], loc="upper center", ncol=2, fontsize=7,
                                  bbox_to_anchor=((j + 0.5) / len(keys), 1.0), frameon=False,
                                  title=series.label(key), title_fontsize=7.5)
        legend_ax.add_artist(legend)
    if any_missing:
        legend_ax.text(0.5, 0.0, "× : not measured at that setting", ha="center", va="bottom",
                       fontsize=7, transform=legend_ax.transAxes)
    return fig


def ms_text(v):
    return f"{v:.3g} ms" if v < 100 else f"{v:.0f} ms"


def error_groups(rows, series):
    """The cells of one panel, grouped by setting: [(cells, one)] where one is True when the
    cells' errors agree within compare.PARETO_RTOL (the same image up to float rounding), so
    that they are drawn as one point, not overprinted."""
    by = {}
    for r in rows:
        by.setdefault(error_setting(r), []).append(r)
    out = []
    for cells in by.values():
        errors = [r["rmse"] for r in cells]
        out.append((sorted(cells, key=lambda r: r["device_ms"]),
                    max(errors) <= min(errors) * (1 + PARETO_RTOL) or max(errors) == 0))
    return out


def speed_vs_accuracy(meta, rows):
    """Device ms against RMSE, a panel per scene. Where the designs' errors at a setting agree
    within compare.PARETO_RTOL (the same image), the setting is one point, in the colour and
    marker of its fastest design, with a grey line to its slowest: their points would share a
    height and overprint. Where they differ, a point per design. The Pareto front joins points
    only where the error drops by more than PARETO_RTOL. The title counts exactly equal errors
    apart from errors equal only once rounded (compare.error_agreement). A series of the sweep
    without accuracy cells is named in the legend as missing."""
    every = Series(rows)
    rows = [r for r in in_group(rows, "accuracy") if r.get("rmse") is not None]
    if not rows:
        return None
    ref = rows[0].get("reference", {})
    # Keyed as in the whole sweep, so that a layout without accuracy cells is named, not lost.
    series, scenes = every, scenes_of(rows)
    present = {series.key(r) for r in rows}
    absent = [series.label(k) for k in series.keys if k not in present]
    a = error_agreement(rows)
    note = ""
    if a["settings"] and a["equal"] == a["settings"]:
        note = f"\nerrors of the designs exactly equal at all {a['settings']} settings"
    elif a["settings"]:
        note = (f"\nerrors of the designs exactly equal at {a['equal']} of {a['settings']} "
                f"settings, equal once rounded to {ERROR_DECIMALS} decimals at {a['rounded']} "
                f"more, apart at {a['differ']} (largest gap {a['worst']:.1g} relative)")
    # Rows since issue 51 are scored against the independent oracle and carry the acne rate.
    oracle = ref.get("pipeline") == "oracle"
    who = ("the independent oracle (core/SHADING.md 3)" if oracle
           else "the converged CPU reference, which shares the renderers' method")
    fig, panels, legend_ax = figure(
        meta, f"Speed against accuracy (error from {who}, log-log)\n"
        f"reference: {'oracle' if oracle else 'CPU'} double, B={ref.get('bounces')}, "
        f"{ref.get('shadow_samples')} shadow samples, aa={ref.get('aa')}" + note, len(scenes),
        legend_rows=2.2)
    labelled, shown = [], set()
    for ax, scene in zip(panels, scenes):
        srows = [r for r in rows if r["scene"] == scene]
        for cells, one in error_groups(srows, series):
            drawn = cells[:1] if one else cells
            shown |= {series.key(r) for r in drawn}
            if one and len(cells) > 1:
                ax.plot([cells[0]["device_ms"], cells[-1]["device_ms"]],
                        [max(cells[0]["rmse"], 1e-6)] * 2, color="#aaaaaa", linewidth=0.9,
                        zorder=1)
            for r in drawn:
                st = series_style(series, series.key(r))
                ax.scatter([r["device_ms"]], [max(r["rmse"], 1e-6)], s=24, marker=st["marker"],
                           color=st["color"], linewidths=0, zorder=3)
        front = pareto([(r["device_ms"], max(r["rmse"], 1e-6), r) for r in srows])
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="black",
                linewidth=1.1)
        ax.scatter([p[0] for p in front], [p[1] for p in front], s=70, facecolors="none",
                   edgecolors="black", linewidths=1.0)
        acne = [r["acne_2_255"] for r in srows if r.get("acne_2_255") is not None]
        acne_text = f"; acne up to {100 * max(acne):.2f}% of pixels" if acne else ""
        ax.set_title(f"{scene} ({srows[0]['width']}×{srows[0]['height']}){acne_text}",
                     fontsize=9)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("device ms per frame")
        ax.set_ylabel("RMSE (linear, clamped to [0,1])")
        ax.grid(True, which="both", alpha=0.3)
        log_ticks(ax, "x")
        log_ticks(ax)
        labelled.append((ax, front))
    handles, labels = [], []
    for k in (k for k in series.keys if k in present):
        st = series_style(series, k)
        handles.append(Line2D([], [], linestyle="none", marker=st["marker"], color=st["color"]))
        # A design never the fastest of a shared error has no marker of its own: say so.
        labels.append(series.label(k) + ("" if k in shown else ": never the fastest, inside "
                                         "the grey lines"))
    for name in absent:
        handles.append(Line2D([], [], linestyle="none", marker=MISSING_MARKER, color="#777777"))
        labels.append(f"{name}: not measured in this sweep's accuracy cells")
    handles.append(Line2D([], [], color="#aaaaaa", linewidth=0.9))
    labels.append("one setting, errors within 1%: its fastest design's marker, a line to the "
                  "slowest design's time")
    handles.append(Line2D([], [], color="black", marker="o", markerfacecolor="none"))
    labels.append(f"Pareto front (errors within {PARETO_RTOL:.0%} are one level; labelled: B "
                  "bounce limit, s shadow samples, aa)")
    legend_row(legend_ax, handles, labels, ncol=min(len(labels), 3))
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
    from . import charts_crossover
    from . import charts_limits
    rows = [r for r in all_rows if failure(r) == ""]
    figs = {name: chart(meta, rows) for name, chart in CHARTS.items()}
    figs["limits.png"] = charts_limits.limits_chart(meta, all_rows)
    figs["crossover.png"] = charts_crossover.crossover_chart(meta, all_rows)
    return figs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json")
    ap.add_argument("--out", help="output folder [the JSON's folder]")
    args = ap.parse_args(argv)
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

