"""Where the persistent megakernel's time goes, beside the queue wavefront's kernels on the same
scenes: one stacked bar per design and scene, in the weighted megakernel's time (so that the
issue's 2x bar is the line at 0.5).

The persistent rows come from a sweep built with -DRT_PERSIST_PHASE_CLOCKS (its cl-options; a
diagnostic: each warp of the counting frame adds its cycles per phase of the regrouped loop's
step or of the bounce loop's passes to the row's extras, phase_mcycles_*). A phase's share of
those cycles times the row's device time (the timed frames, which run without the clocks) is its
milliseconds. The queue rows give their kernels' own times (kernel_ms): the extension rays'
trace, the shadow rays, the shading, and the rest (compaction, scans, accumulation). Queue rows
in the phase rows' file make a bar labelled "queue"; each --queue LABEL=ROWS adds one more a
scene (e.g. the queue with its rays scattered).

Where the shadow rays go: the queue casts them in a kernel of its own, and so does the bounce
loop with --persistent-shadows pass. The regrouped loop and the bounce loop without a shadow
pass cast a hit's shadow rays in its trace (RayTree_TraceNode), so their trace phase is the
queue's extend and shadow kernels together: the table sets "trace and shadow rays" side by side
for every design, and says how much of it the shadow rays are where they are apart.
Writes phases.md and phases.png.

Usage: python3 -m rtlab_report phase-charts PHASE_ROWS.jsonl [--queue LABEL=ROWS.jsonl ...] [--out DIR]
Needs Debian's python3-matplotlib for the chart; the table needs nothing.
"""
import argparse
import os
import sys

from .charts_map import load
from .charts_persist import as_old_fields

# The phases of the regrouped loop's step and of the bounce loop's passes (RT_PHASE_*,
# persistent/phases.h), as the rows' extras name them.
PHASES = ["bookkeeping", "trace", "trace_wait", "file", "shade", "shade_wait", "shadow",
          "shadow_wait"]
WAITS = ["trace_wait", "shadow_wait", "shade_wait"]
# A bar's parts, in the order they are stacked.
TRACE = "trace (extension rays)"
TRACE_WITH_SHADOWS = "trace, with its shadow rays"
SHADOWS = "shadow rays"
PARTS = [TRACE, TRACE_WITH_SHADOWS, SHADOWS, "shading", "waiting at the barriers",
         "filing the hits", "bookkeeping"]
COLORS = {TRACE: "#0072B2", TRACE_WITH_SHADOWS: "#3F4F9F", SHADOWS: "#56B4E9",
          "shading": "#009E73", "waiting at the barriers": "#E69F00",
          "filing the hits": "#CC79A7", "bookkeeping": "#999999"}


# Rows written since the schedules became units (persistent/schedules.h) name them in
# persistent_schedule; older rows set the loop, regrouping, order, batch and shadows apart. Both
# read the same here: a new row gets the older fields its schedule stands for.


def persist_label(row):
    """The persistent row's schedule in words: the bar's name."""
    row = as_old_fields(row)
    regroup = row.get("persistent_regroup") or "off"
    if row.get("persistent_loop") == "bounce":
        words = ["bounce loop"]
        if regroup != "off":
            words.append("sorted by " + regroup)
        if row.get("persistent_shadows") == "pass":
            words.append("shadow pass")
        return ", ".join(words)
    if regroup != "off":
        return "regrouped by " + regroup
    return "persistent, " + row.get("persistent_loop", "flat") + " loop"


def phase_ms(row):
    """{phase: ms} of a persistent row, or None without the clocks."""
    extras = row.get("extras", {})
    cycles = {key: extras.get("phase_mcycles_" + key, 0.0) for key in PHASES}
    total = sum(cycles.values())
    if total <= 0:
        return None
    return {key: row["device_ms"] * c / total for key, c in cycles.items()}


def persist_parts(row):
    """[(part, ms)] of a persistent row: its trace split from its shadow rays where a shadow pass
    casts them, the barrier waits together."""
    ms = phase_ms(row)
    apart = ms["shadow"] > 0 or row.get("persistent_shadows") == "pass"
    trace = [(TRACE, ms["trace"]), (SHADOWS, ms["shadow"])] if apart else [
        (TRACE_WITH_SHADOWS, ms["trace"])]
    return trace + [("shading", ms["shade"]),
                    ("waiting at the barriers", sum(ms[w] for w in WAITS)),
                    ("filing the hits", ms["file"]), ("bookkeeping", ms["bookkeeping"])]


def queue_parts(row):
    """[(part, ms)] of a queue row: its extend, shadow, shade and other kernels."""
    k = row.get("kernel_ms", {})
    trace = k.get("extend", 0.0)
    shadow = k.get("shadow", 0.0)
    shading = sum(v for name, v in k.items() if name.startswith("shade"))
    return [(TRACE, trace), (SHADOWS, shadow), ("shading", shading),
            ("bookkeeping", max(0.0, row["device_ms"] - trace - shadow - shading))]


def gather(phase_rows, queues):
    """(scenes, {scene: {"mega": row, "bars": [(label, row, parts)]}}) for the scenes with a
    persistent row that has phase clocks and a weighted-megakernel row. Bars: the persistent
    rows in sweep order, then the queue's."""
    grid, scenes = {}, []
    for r in phase_rows:
        if r.get("status", "ok") != "ok":
            continue
        g = grid.setdefault(r["scene"], {"bars": []})
        if r["pipeline"] == "mega" and r.get("layout") == "weighted":
            g["mega"] = r
        elif r["pipeline"] == "persist" and phase_ms(r):
            g["bars"].append((persist_label(r), r, persist_parts(r)))
            scenes += [r["scene"]] if r["scene"] not in scenes else []
    for label, rows in [("queue", phase_rows)] + queues:
        for r in rows:
            if r["pipeline"] == "queue" and r.get("status", "ok") == "ok" and r["scene"] in grid:
                grid[r["scene"]]["bars"].append((label, r, queue_parts(r)))
    return [s for s in scenes if "mega" in grid[s]], grid


def short(scene):
    return scene.split("/")[-1].replace("map-", "").replace("-m16", "")


def cells(parts):
    """The table's columns of one bar: trace and shadow rays, of which shadow rays, shading,
    waiting, filing, bookkeeping ("in the trace" / "—" where the design has no such part)."""
    p = dict(parts)
    both = p.get(TRACE, 0.0) + p.get(SHADOWS, 0.0) + p.get(TRACE_WITH_SHADOWS, 0.0)
    shadows = f"{p[SHADOWS]:.2f}" if SHADOWS in p else "in the trace"
    return [f"{both:.2f}", shadows, f"{p['shading']:.2f}"] + [
        f"{p[k]:.2f}" if k in p else "—"
        for k in ("waiting at the barriers", "filing the hits", "bookkeeping")]


def table(meta, scenes, grid, path):
    head = ["scene", "design", "ms (speed-up)", "trace and shadow rays", "of which shadow rays",
            "shading", "waiting at the barriers", "filing the hits", "bookkeeping"]
    lines = [f"# Where the time goes: the persistent megakernel and the queue wavefront, "
             f"{meta.get('device')}", "",
             f"Driver {meta.get('driver')}, commit `{meta.get('commit')}`, sweep "
             f"`{meta.get('sweep')}`; ms. The persistent megakernel's parts: its warps' share of "
             f"cycles in each phase (phase clocks, counting frame) times its device time. The "
             f"queue's: its kernels' device times, its bookkeeping the kernels that are not "
             f"extend, shadow or shade. A persistent loop without a shadow pass casts a hit's "
             f"shadow rays in its trace. Speed-up: over the weighted megakernel of the "
             f"phase rows.", "",
             "| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for sc in scenes:
        g = grid[sc]
        mega = g["mega"]["device_ms"]
        lines.append(f"| `{short(sc)}` | weighted megakernel | {mega:.3f} |" + " |" * 6)
        for label, row, parts in g["bars"]:
            ms = row["device_ms"]
            cols = [f"`{short(sc)}`", label, f"{ms:.3f} ({mega / ms:.2f}x)"] + cells(parts)
            lines.append("| " + " | ".join(cols) + " |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def chart(meta, scenes, grid, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from .chart_style import figure, legend_row

    most = max(len(grid[sc]["bars"]) for sc in scenes)
    fig, panels, legend_ax = figure(
        meta, "Where the time goes, in the weighted megakernel's time: the persistent "
        "megakernel's phases and the queue wavefront's kernels (dashed: 2x faster than the "
        "weighted megakernel)", 1, cols=1,
        panel=(10, 0.32 * len(scenes) * most + 1.0), legend_rows=2.0)
    ax = panels[0]
    height = 0.8 / most
    used = set()
    for i, sc in enumerate(scenes):
        g = grid[sc]
        mega = g["mega"]["device_ms"]
        for j, (label, _, parts) in enumerate(g["bars"]):
            y = i + height * (j + 0.5) - 0.4
            left = 0.0
            for part, ms in parts:
                ax.barh(y, ms / mega, left=left, height=height * 0.9, color=COLORS[part],
                        edgecolor="white", linewidth=0.4)
                left += ms / mega
                used.add(part)
            ax.text(left + 0.01, y, label, va="center", fontsize=7)
    ax.axvline(0.5, color="black", linestyle="--", linewidth=0.8)
    ax.axvline(1.0, color="black", linewidth=0.8)
    ax.set_yticks(range(len(scenes)), [short(sc) for sc in scenes], fontsize=8)
    ax.set_ylim(len(scenes) - 0.5, -0.5)
    ax.set_xlabel("time / the weighted megakernel's time", fontsize=8)
    handles = [Patch(facecolor=COLORS[p], label=p) for p in PARTS if p in used]
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=4)
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rows", help="rows.jsonl of a sweep run with -DRT_PERSIST_PHASE_CLOCKS")
    ap.add_argument("--queue", action="append", default=[], metavar="LABEL=ROWS",
                    help="queue wavefront rows to set beside it, under a label")
    ap.add_argument("--out", default=None, help="folder for phases.md and phases.png "
                    "[beside the rows]")
    a = ap.parse_args(argv)
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
    table(meta, scenes, grid, os.path.join(out, "phases.md"))
    try:
        chart(meta, scenes, grid, os.path.join(out, "phases.png"))
    except ImportError:
        print("charts_phases: no matplotlib (scripts/setup installs it): table only",
              file=sys.stderr)
    print(os.path.join(out, "phases.md"))

