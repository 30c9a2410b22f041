#!/usr/bin/env python3
"""Where the regrouped persistent megakernel's time goes, beside the queue wavefront's kernels on
the same scenes: one stacked bar per design and scene, in the weighted megakernel's time (so that
the issue's 2x bar is the line at 0.5).

The persistent rows come from a sweep run with RTLAB_CL_OPTIONS=-DRT_PERSIST_PHASE_CLOCKS (an
experiment: each warp of the counting frame adds its cycles per phase of a regrouped step to the
row's extras, phase_mcycles_*). A phase's share of those cycles times the row's device time (the
timed frames, which run without the clocks) is its milliseconds. The queue rows give their
kernels' own times (kernel_ms): the extension rays' trace, the shadow rays, the shading, and the
rest (compaction, scans, accumulation). Each --queue LABEL=ROWS adds one bar a scene (e.g. the
queue as it is and with its rays scattered). Writes phases.md and phases.png.

Usage: scripts/charts_phases.py PHASE_ROWS.jsonl [--queue LABEL=ROWS.jsonl ...] [--out DIR]
Needs Debian's python3-matplotlib for the chart; the table needs nothing.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from charts_map import load  # noqa: E402

# The regrouped step's phases (persistent.cl), in the order a step runs them.
PHASES = [("bookkeeping", "bookkeeping (pixels, stacks)"), ("trace", "trace"),
          ("trace_wait", "waiting after the trace"), ("file", "filing the hits"),
          ("shade", "shading"), ("shade_wait", "waiting after the shading")]
# The queue's kernels by part (core/cl and wavefront/queue kernel names, as kernel_ms has them).
QUEUE_PARTS = ["trace", "shadow rays", "shading", "other"]
COLORS = {"bookkeeping (pixels, stacks)": "#999999", "trace": "#0072B2",
          "waiting after the trace": "#F0E442", "filing the hits": "#CC79A7",
          "shading": "#009E73", "waiting after the shading": "#E69F00", "shadow rays": "#56B4E9",
          "other": "#D55E00"}


def phase_ms(row):
    """[(label, ms)] of a persistent row's phases, or None without the clocks."""
    cycles = [row.get("extras", {}).get("phase_mcycles_" + key, 0.0) for key, _ in PHASES]
    total = sum(cycles)
    if total <= 0:
        return None
    return [(label, row["device_ms"] * c / total) for (_, label), c in zip(PHASES, cycles)]


def queue_ms(row):
    """[(part, ms)] of a queue row: its trace, shadow, shading and other kernels."""
    k = row.get("kernel_ms", {})
    trace = k.get("extend", 0.0)
    shadow = k.get("shadow", 0.0)
    shading = sum(v for name, v in k.items() if name.startswith("shade"))
    return list(zip(QUEUE_PARTS, [trace, shadow, shading,
                                  max(0.0, row["device_ms"] - trace - shadow - shading)]))


def gather(phase_rows, queues):
    """(scenes, {scene: {"mega": row, "persist": row, label: queue row}}) for the scenes whose
    persistent row has phase clocks and that have a weighted-megakernel row."""
    grid, scenes = {}, []
    for r in phase_rows:
        if r.get("status", "ok") != "ok":
            continue
        g = grid.setdefault(r["scene"], {})
        if r["pipeline"] == "mega" and r.get("layout") == "weighted":
            g["mega"] = r
        elif r["pipeline"] == "persist" and phase_ms(r):
            g["persist"] = r
            scenes += [r["scene"]] if r["scene"] not in scenes else []
    for label, rows in queues:
        for r in rows:
            if r["pipeline"] == "queue" and r.get("status", "ok") == "ok" and r["scene"] in grid:
                grid[r["scene"]][label] = r
    return [s for s in scenes if "mega" in grid[s]], grid


def short(scene):
    return scene.split("/")[-1].replace("map-", "").replace("-m16", "")


def table(meta, scenes, grid, labels, path):
    head = ["scene", "weighted megakernel", "persist (regrouped)"] + [
        f"persist: {lab}" for _, lab in PHASES] + [f"{q}: {p}" for q in labels for p in ["total"] + QUEUE_PARTS]
    lines = [f"# Where the time goes: the regrouped persistent megakernel and the queue "
             f"wavefront, {meta.get('device')}", "",
             f"Driver {meta.get('driver')}, commit `{meta.get('commit')}`, sweep "
             f"`{meta.get('sweep')}`; ms. The persistent megakernel's phases: its warps' share "
             f"of cycles in each (phase clocks, counting frame) times its device time; its shading "
             f"casts the shadow rays. The queue's: its kernels' device times. Speed-up in brackets: over the weighted megakernel.", "",
             "| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for sc in scenes:
        g = grid[sc]
        mega = g["mega"]["device_ms"]
        cols = [f"`{short(sc)}`", f"{mega:.3f}",
                f"{g['persist']['device_ms']:.3f} ({mega / g['persist']['device_ms']:.2f}x)"]
        cols += [f"{ms:.2f}" for _, ms in phase_ms(g["persist"])]
        for q in labels:
            if q in g:
                cols += [f"{g[q]['device_ms']:.3f} ({mega / g[q]['device_ms']:.2f}x)"]
                cols += [f"{ms:.2f}" for _, ms in queue_ms(g[q])]
            else:
                cols += ["—"] * (1 + len(QUEUE_PARTS))
        lines.append("| " + " | ".join(cols) + " |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def chart(meta, scenes, grid, labels, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from chart_style import figure, legend_row

    bars = ["persist"] + labels
    fig, panels, legend_ax = figure(
        meta, "Where the time goes, in the weighted megakernel's time: the regrouped persistent "
        "megakernel's step phases (its shading casts the shadow rays) and the queue wavefront's "
        "kernels (dashed: 2x faster than the weighted megakernel)", 1, cols=1,
        panel=(10, 0.32 * len(scenes) * len(bars) + 1.0), legend_rows=2.0)
    ax = panels[0]
    height = 0.8 / len(bars)
    ticks, names = [], []
    for i, sc in enumerate(scenes):
        g = grid[sc]
        mega = g["mega"]["device_ms"]
        for j, bar in enumerate(bars):
            if bar not in g:
                continue
            y = i + height * (j + 0.5) - 0.4
            parts = phase_ms(g[bar]) if bar == "persist" else queue_ms(g[bar])
            left = 0.0
            for label, ms in parts:
                ax.barh(y, ms / mega, left=left, height=height * 0.9, color=COLORS[label],
                        edgecolor="white", linewidth=0.4)
                left += ms / mega
            ax.text(left + 0.01, y, "persistent" if bar == "persist" else bar, va="center",
                    fontsize=7)
        ticks.append(i)
        names.append(short(sc))
    ax.axvline(0.5, color="black", linestyle="--", linewidth=0.8)
    ax.axvline(1.0, color="black", linewidth=0.8)
    ax.set_yticks(ticks, names, fontsize=8)
    ax.set_ylim(len(scenes) - 0.5, -0.5)
    ax.set_xlabel("time / the weighted megakernel's time", fontsize=8)
    seen = [lab for _, lab in PHASES] + [p for p in QUEUE_PARTS if p not in ("trace", "shading")]
    assert all(lab in COLORS for lab in seen + QUEUE_PARTS)
    handles = [Patch(facecolor=COLORS[lab], label=lab) for lab in seen]
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=5)
    fig.savefig(path)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rows", help="rows.jsonl of a sweep run with -DRT_PERSIST_PHASE_CLOCKS")
    ap.add_argument("--queue", action="append", default=[], metavar="LABEL=ROWS",
                    help="queue wavefront rows to set beside it, under a label")
    ap.add_argument("--out", default=None, help="folder for phases.md and phases.png "
                    "[beside the rows]")
    a = ap.parse_args()
    meta, rows = load(a.rows)
    queues = []
    for spec in a.queue:
        label, sep, path = spec.partition("=")
        if not sep or not label or not path:
            sys.exit(f"--queue {spec}: expected LABEL=ROWS.jsonl")
        if not os.path.exists(path):
            sys.exit(f"--queue {spec}: {path}: no such file")
        queues.append((label, load(path)[1]))
    scenes, grid = gather(rows, queues)
    if not scenes:
        sys.exit(f"{a.rows}: no persistent rows with phase clocks (phase_mcycles_*) beside a "
                 "weighted-megakernel row")
    out = a.out or os.path.dirname(os.path.abspath(a.rows))
    os.makedirs(out, exist_ok=True)
    labels = [label for label, _ in queues]
    table(meta, scenes, grid, labels, os.path.join(out, "phases.md"))
    try:
        chart(meta, scenes, grid, labels, os.path.join(out, "phases.png"))
    except ImportError:
        print("charts_phases: no matplotlib (scripts/setup installs it): table only",
              file=sys.stderr)
    print(os.path.join(out, "phases.md"))


if __name__ == "__main__":
    main()
