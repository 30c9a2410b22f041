"""Draws the persistent megakernel's schedules against the weighted megakernel, whose per-pixel
code they share, from a `persist` or `persist-loop` sweep (bench/sweeps/): for each scene, the
speed-up of each schedule (flat, nested, lockstep, regrouped by pattern or by material, among
128 or 256 lanes) and of the other designs over the weighted megakernel, on a log axis with the
issue's 2x target marked. A speed-up inside the measured frame spread (compare.py's tie rule) is
drawn hollow. Also writes a Markdown table beside the chart, both named after the sweep
(persist.md, persist.png), with every time (the 64-lane, tree-megakernel and one-group series
too) and the best schedule's speed-up per scene. scripts/gpu-sweep.sh import runs it for these sweeps.

Where the weighted megakernel's row counted its warps (NVIDIA: the extra warp_lanes_active, its
busy lanes of 32 a warp step), the table and chart also give the idle-lane bound, 32 over those
lanes: the most that filling the megakernel's idle lanes with the same per-ray code would gain,
if its steps cost what they do. A schedule past it made the steps themselves cheaper (sorting
the shading); one short of 2x where the bound is too cannot reach 2x by keeping lanes busy alone.

A sweep about the order pixels are handed out in (every schedule it runs is in several
--persistent-tile orders, as in the persist-tile sweep) gets a table and chart by tile instead:
for each schedule and scene, the time at each order and the speed-up of the best one.

Usage: python3 -m rtlab_report persist-charts ROWS.jsonl|SWEEP.json [--out DIR]
Needs Debian's python3-matplotlib for the chart; the table needs nothing.
"""
import argparse
import os
import sys

from .charts_map import load  # rows.jsonl beside its sweep.json, or a sweep JSON
from .compare import tied

BASE = "weighted megakernel"
TARGET = 2.0  # the bar on divergent scenes



# Rows written since the schedules became units (persistent/schedules.h) name them in
# persistent_schedule; older rows set the loop, regrouping, order, batch and shadows apart. Both
# read the same here: a new row gets the older fields its schedule stands for.
SCHEDULE_FIELDS = {
    "flat": {},
    "nested": {"persistent_loop": "nested"},
    "nested-16x8": {"persistent_loop": "nested", "persistent_tile": "16x8"},
    "regrouped": {"persistent_regroup": "pattern"},
    "bounce": {"persistent_loop": "bounce"},
    "bounce-staged": {"persistent_loop": "bounce", "persistent_regroup": "pattern",
                      "persistent_shadows": "pass"},
}


def as_old_fields(row):
    """`row` with the fields of older rows that its persistent_schedule stands for."""
    fields = SCHEDULE_FIELDS.get(row.get("persistent_schedule"))
    if fields is None:
        return row
    out = dict(row)
    out.update(fields)
    if out.get("persistent_loop") == "bounce":  # batches of twice its lanes
        out.setdefault("persistent_batch", 2 * (row.get("persistent_lanes") or 512))
    return out

def series_of(r, strips=True):
    """The series a row belongs to (None: a refill scan the chart and table leave out; names not
    in ORDER, the other work-group counts, are left out too). With `strips`, an order other than
    the default 4x16 names a series of its own (rows without the field ran at 8x4 and keep their
    names)."""
    p = r["pipeline"]
    if p == "mega":
        if r.get("layout") != "weighted":
            return "tree megakernel"
        return BASE + (f", {r['max_registers']} registers" if r.get("max_registers") else "")
    if p == "queue":
        return "queue wavefront"
    if p == "wave":
        return "tree wavefront"
    if p != "persist":
        return None
    if r.get("persistent_schedule", "flags") == "auto":
        return AUTO  # the schedule it chose is in the row's extras, not its flags
    r = as_old_fields(r)
    regroup = r.get("persistent_regroup", "off")
    lanes = r.get("persistent_lanes") or 128
    groups, refill = r.get("persistent_groups", 4), r.get("persistent_refill", 1)
    regs = r.get("persistent_max_registers") or 0
    units = (f", {regs} registers" if regs else "") + (
        f", {groups} group{'s' if groups > 1 else ''} a unit")
    tile = r.get("persistent_tile", "4x16")
    order = f", {tile} strips" if strips and tile != "4x16" else ""
    if r.get("persistent_loop", "flat") == "nested":
        return "persist, nested loop" + (units if groups != 4 or regs else "") + order
    if r.get("persistent_loop", "flat") == "lockstep":
        return "persist, lockstep loop" + (units if groups != 4 or regs else "") + order
    if r.get("persistent_loop", "flat") == "bounce":
        return (f"{BOUNCE}, {r.get('persistent_batch', 1024)} px batches, {lanes} lanes" + units +
                order)
    if regroup == "off":
        if refill == 1:
            return "persist, flat" + (units if groups != 4 or regs else "") + order
        if groups == 4 and refill == 32:
            return "persist, flat, whole-warp refill" + order
        return None
    # Work-groups a unit chosen so that each unit is offered 512 work-items, or not.
    return f"persist, regrouped by {regroup}, {lanes} lanes" + (
        units if groups * lanes != 512 or regs else "") + order


AUTO = "persist, auto schedule"
# The bounce loop's settings (batch, lanes, groups, registers) are series of their own, in the
# table in sweep order; the chart draws the fastest of them per scene as one series.
BOUNCE = "persist, bounce loop"
BOUNCE_BEST = BOUNCE + ", the fastest setting"
CAPPED = BASE + ", 64 registers"
ORDER = ["persist, flat", "persist, flat, whole-warp refill", "persist, nested loop",
         "persist, nested loop, 16x8 strips",
         "persist, nested loop, 64 registers, 4 groups a unit",
         "persist, nested loop, 8 groups a unit",
         "persist, flat, 1 group a unit",
         "persist, flat, 64 registers, 8 groups a unit",
         "persist, regrouped by pattern, 128 lanes", "persist, regrouped by material, 128 lanes",
         "persist, regrouped by material, 64 lanes", "persist, regrouped by material, 256 lanes",
         "persist, regrouped by pattern, 128 lanes, 2 groups a unit",
         "persist, regrouped by pattern, 128 lanes, 1 group a unit",
         "persist, regrouped by pattern, 128 lanes, 96 registers, 5 groups a unit",
         "persist, regrouped by pattern, 128 lanes, 64 registers, 8 groups a unit",
         "persist, regrouped by pattern, 256 lanes, 128 registers, 2 groups a unit",
         "persist, regrouped by material, 256 lanes, 128 registers, 2 groups a unit",
         "persist, regrouped by material, 192 lanes, 2 groups a unit",
         "persist, regrouped by pattern, 256 lanes, 120 registers, 2 groups a unit",
         "persist, regrouped by pattern, 128 lanes, 128 registers, 4 groups a unit",
         "persist, regrouped by pattern, 128 lanes, 96 registers, 4 groups a unit",
         "persist, regrouped by pattern, 256 lanes, 80 registers, 3 groups a unit",
         "persist, regrouped by pattern, 256 lanes, 64 registers, 4 groups a unit",
         "persist, regrouped by pattern, 128 lanes, 80 registers, 6 groups a unit",
         "persist, flat, 2 groups a unit", "persist, flat, 8 groups a unit",
         "persist, flat, 16 groups a unit", AUTO, "persist, lockstep loop",
         "persist, lockstep loop, 128 registers, 4 groups a unit",
         "persist, lockstep loop, 64 registers, 8 groups a unit",
         CAPPED, "tree megakernel", "tree wavefront", "queue wavefront"]
# The chart draws these; the table lists every series above. Colours from the one palette
# (chart_style): the persistent megakernel's schedules in shades of its own colour, the other
# designs in theirs.
DRAWN_PERSIST = ["persist, flat", "persist, flat, whole-warp refill", "persist, nested loop",
                 "persist, nested loop, 16x8 strips",
                 "persist, flat, 64 registers, 8 groups a unit",
                 "persist, regrouped by pattern, 128 lanes",
                 "persist, regrouped by material, 256 lanes",
                 "persist, regrouped by pattern, 256 lanes, 128 registers, 2 groups a unit",
                 "persist, regrouped by pattern, 256 lanes, 80 registers, 3 groups a unit",
                 "persist, regrouped by pattern, 256 lanes, 64 registers, 4 groups a unit",
                 "persist, lockstep loop", "persist, lockstep loop, 128 registers, 4 groups a unit",
                 BOUNCE_BEST]
DRAWN = {s: ("persist", i) for i, s in enumerate(DRAWN_PERSIST)}
DRAWN.update({AUTO: ("auto", 0), CAPPED: ("mega-weighted", 0), "tree wavefront": ("wave", 0),
              "queue wavefront": ("queue", 0)})


def drawn_color(s):
    from .chart_style import design_color, variant_color
    design, i = DRAWN[s]
    if design == "mega-weighted":
        return design_color("mega", "weighted")
    return variant_color(design, i) if design == "persist" else design_color(design)


def cells(rows):
    """(scenes in sweep order, {scene: {series: row}})."""
    scenes, out = [], {}
    for r in rows:
        s = series_of(r)
        known = s in ORDER or (s or "").startswith(BOUNCE)
        if (s != BASE and not known) or r.get("status", "ok") != "ok":
            continue
        if r["scene"] not in out:
            scenes.append(r["scene"])
        out.setdefault(r["scene"], {})[s] = r
    return scenes, out


def short(scene):
    return scene.replace("map/", "").replace("-m16", "")


def busy_lanes(base):
    """The weighted megakernel's busy lanes of 32 a warp step, or None where its row did not
    count them (the counter is NVIDIA's: core/types.h, RT_COUNT_LANES_ACTIVE). 32 over them is
    the idle-lane bound."""
    return (base or {}).get("extras", {}).get("warp_lanes_active") or None


def speed_up(base, row):
    """base's time over row's, "(tie)" when inside the frame spread."""
    return f"{base['device_ms'] / row['device_ms']:.2f}x" + (" (tie)" if tied(base, row) else "")


def bounce_series(scenes, grid):
    """The bounce loop's settings that ran, in sweep order."""
    out = []
    for sc in scenes:
        out += [s for s in grid[sc] if s.startswith(BOUNCE) and s not in out]
    return out


def table(meta, scenes, grid, path):
    present = ([s for s in ORDER if any(s in grid[sc] for sc in scenes)] +
               bounce_series(scenes, grid))
    lines = [f"# Persistent megakernel schedules, {meta.get('device')}", "",
             f"Driver {meta.get('driver')}, commit `{meta.get('commit')}`, sweep "
             f"`{meta.get('sweep')}`; median device time of the frames in ms. Speed-up: the "
             f"weighted megakernel's time over the fastest persistent schedule's, at the "
             f"compiler's registers and at the better of that and a cap of 64 where the sweep "
             f"has it; (tie) when the two lie inside each other's frame spread. Idle-lane "
             f"bound: 32 over the weighted megakernel's busy lanes a warp step, the most that "
             f"filling its idle lanes with the same per-ray code would gain (— where the device "
             f"did not count them).", "",
             "| scene | " + " | ".join([BASE] + present) +
             " | best persist | speed-up | over the better weighted build | idle-lane bound |",
             "|---" * (len(present) + 6) + "|"]
    for sc in scenes:
        g = grid[sc]
        base = g.get(BASE)
        persists = [s for s in present if s.startswith("persist") and s in g]
        best = min(persists, key=lambda s: g[s]["device_ms"]) if persists else None
        cols = [f"{g[s]['device_ms']:.2f}" if s in g else "—" for s in [BASE] + present]
        if base and best:
            tail = [best.replace("persist, ", ""), speed_up(base, g[best])]
            better = min((g[k] for k in (BASE, CAPPED) if k in g), key=lambda r: r["device_ms"])
            tail.append(speed_up(better, g[best]))
        else:
            tail = ["—", "—", "—"]
        lanes = busy_lanes(base)
        tail.append(f"{32 / lanes:.2f}x ({lanes:.1f} lanes)" if lanes else "—")
        lines.append(f"| `{sc}` | " + " | ".join(cols + tail) + " |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def chart(meta, scenes, grid, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from .chart_style import figure, legend_row, log_ticks

    bounce = bounce_series(scenes, grid)
    if bounce:
        grid = {sc: dict(g) for sc, g in grid.items()}
        for sc, g in grid.items():
            ran = [g[s] for s in bounce if s in g]
            if ran:
                g[BOUNCE_BEST] = min(ran, key=lambda r: r["device_ms"])
    present = [s for s in ORDER + [BOUNCE_BEST]
               if s in DRAWN and any(s in grid[sc] for sc in scenes)]
    r0 = next(iter(grid[scenes[0]].values()))
    fig, (ax,), legend_ax = figure(
        meta, f"Speed-up over the weighted megakernel, the persistent megakernel's schedules "
        f"and the wavefronts ({r0['width']}x{r0['height']}, B = {r0['bounces']}); hollow: a "
        f"tie", 1, cols=1, panel=(10, 0.1 * len(scenes) * len(present) + 1.0),
        legend_rows=1.6)
    height = 0.8 / len(present)
    missing = False
    for j, s in enumerate(present):
        color = drawn_color(s)
        for i, sc in enumerate(scenes):
            g = grid[sc]
            if s not in g or BASE not in g:
                # Not measured (or no weighted megakernel to set it against): a cross at 1.
                ax.plot([1], [i - 0.4 + height * (j + 0.5)], marker="x", ms=4, color=color,
                        linestyle="none")
                missing = True
                continue
            up = g[BASE]["device_ms"] / g[s]["device_ms"]
            tie = tied(g[BASE], g[s])
            y = i - 0.4 + height * (j + 0.5)
            ax.barh(y, up - 1 if up >= 1 else -(1 - up), left=1, height=height * 0.9,
                    color="white" if tie else color, edgecolor=color, linewidth=1)
    bounded = False
    for i, sc in enumerate(scenes):
        lanes = busy_lanes(grid[sc].get(BASE))
        if lanes:
            ax.plot([32 / lanes] * 2, [i - 0.45, i + 0.45], color="black", linestyle=":",
                    linewidth=1.2)
            bounded = True
    ax.set_xscale("log")
    ax.axvline(1, color="black", linewidth=0.8)
    ax.axvline(TARGET, color="#999999", linestyle="--", linewidth=0.8)
    ax.text(TARGET, -0.95, " 2x: the issue's target", fontsize=7, color="#555555", va="top")
    ax.set_yticks(range(len(scenes)), [short(sc) for sc in scenes], fontsize=8)
    ax.set_ylim(len(scenes) - 0.5, -1)
    ax.set_xlabel("weighted megakernel's time / this design's time (log; right of 1: faster)")
    log_ticks(ax, "x")
    handles = [Patch(facecolor=drawn_color(s), label=s) for s in present]
    if missing:
        from matplotlib.lines import Line2D
        handles.append(Line2D([], [], marker="x", color="#555555", linestyle="none",
                              label="not measured on that scene"))
    if bounded:
        from matplotlib.lines import Line2D
        handles.append(Line2D([], [], color="black", linestyle=":", linewidth=1.2,
                              label="idle-lane bound: 32 / the weighted megakernel's busy lanes"))
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=3)
    fig.savefig(path)
    plt.close(fig)


# Tile orders are variants of the persistent megakernel: shades of its colour.
def tile_color(j):
    from .chart_style import variant_color
    return variant_color("persist", j)


def about_order(rows):
    """Whether a sweep is about the order pixels are handed out in: every persistent schedule it
    runs is measured in more than one order (the persist sweep runs only the nested loop in
    two, beside schedules in one)."""
    orders = {}
    for r in rows:
        s = series_of(r, strips=False) if r["pipeline"] == "persist" else None
        if s is not None:
            orders.setdefault(s, set()).add(r.get("persistent_tile", "8x4"))
    return bool(orders) and all(len(o) > 1 for o in orders.values())


def tile_grid(rows):
    """(scenes, schedules, tiles, {scene: {(schedule, tile) or series: row}}) of a sweep that
    varies --persistent-tile; rows without the field ran before it existed (8x4)."""
    scenes, schedules, tiles, out = [], [], [], {}
    for r in rows:
        s = series_of(r, strips=False)
        if s is None or r.get("status", "ok") != "ok":
            continue
        if r["scene"] not in out:
            scenes.append(r["scene"])
        key = s
        if r["pipeline"] == "persist":
            schedule, tile = s.replace("persist, ", ""), r.get("persistent_tile", "8x4")
            schedules += [schedule] if schedule not in schedules else []
            tiles += [tile] if tile not in tiles else []
            key = (schedule, tile)
        out.setdefault(r["scene"], {})[key] = r
    return scenes, schedules, tiles, out


def tile_table(meta, scenes, schedules, tiles, grid, path):
    lines = [f"# The persistent megakernel's pixel order, {meta.get('device')}", "",
             f"Driver {meta.get('driver')}, commit `{meta.get('commit')}`, sweep "
             f"`{meta.get('sweep')}`; median device time of the frames in ms, by the strips "
             f"pixels are handed out in (`--persistent-tile WxH`). Speed-up: the weighted "
             f"megakernel's time over the best order's; (tie) inside the frame spread.", "",
             "| scene | schedule | " + " | ".join(tiles) + " | best | speed-up | "
             + BASE + " | queue wavefront |", "|---" * (len(tiles) + 6) + "|"]
    for sc in scenes:
        g = grid[sc]
        for schedule in schedules:
            here = [t for t in tiles if (schedule, t) in g]
            if not here:
                continue
            best = min(here, key=lambda t: g[(schedule, t)]["device_ms"])
            cols = [f"{g[(schedule, t)]['device_ms']:.3f}" if t in here else "—" for t in tiles]
            up = speed_up(g[BASE], g[(schedule, best)]) if BASE in g else "—"
            others = [f"{g[k]['device_ms']:.3f}" if k in g else "—"
                      for k in (BASE, "queue wavefront")]
            lines.append(f"| `{short(sc)}` | {schedule} | " + " | ".join(cols) +
                         f" | {best} | {up} | " + " | ".join(others) + " |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def tile_chart(meta, scenes, schedules, tiles, grid, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from .chart_style import figure, legend_row, log_ticks

    r0 = next(iter(grid[scenes[0]].values()))
    fig, panels, legend_ax = figure(
        meta, f"Speed-up over the weighted megakernel by the order pixels are handed out in "
        f"(--persistent-tile), per schedule ({r0['width']}x{r0['height']}, B = "
        f"{r0['bounces']}); hollow: a tie", len(schedules), cols=2,
        panel=(6, 0.09 * len(scenes) * len(tiles) + 1.0), legend_rows=1.0)
    height = 0.8 / len(tiles)
    for ax, schedule in zip(panels, schedules):
        for j, tile in enumerate(tiles):
            color = tile_color(j)
            for i, sc in enumerate(scenes):
                g = grid[sc]
                if (schedule, tile) not in g or BASE not in g:
                    continue
                row = g[(schedule, tile)]
                up = g[BASE]["device_ms"] / row["device_ms"]
                y = i - 0.4 + height * (j + 0.5)
                ax.barh(y, up - 1 if up >= 1 else -(1 - up), left=1, height=height * 0.9,
                        color="white" if tied(g[BASE], row) else color, edgecolor=color,
                        linewidth=1)
        ax.set_xscale("log")
        ax.axvline(1, color="black", linewidth=0.8)
        ax.set_title(schedule, fontsize=9)
        ax.set_yticks(range(len(scenes)), [short(sc) for sc in scenes], fontsize=8)
        ax.set_ylim(len(scenes) - 0.5, -0.5)
        ax.set_xlabel("weighted megakernel's time / this one's (log)", fontsize=8)
        log_ticks(ax, "x")
    handles = [Patch(facecolor=tile_color(j), label=f"{t} strips")
               for j, t in enumerate(tiles)]
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=len(tiles))
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rows")
    ap.add_argument("--out", default=None, help="folder for <sweep>.png and <sweep>.md "
                    "[beside the rows]")
    a = ap.parse_args(argv)
    meta, rows = load(a.rows)
    out = a.out or os.path.dirname(os.path.abspath(a.rows))
    os.makedirs(out, exist_ok=True)
    name = os.path.join(out, meta.get("sweep") or "persist")  # persist.md, persist-loop.md
    if about_order(rows):
        scenes, schedules, tiles, grid = tile_grid(rows)
        tile_table(meta, scenes, schedules, tiles, grid, name + ".md")
        try:
            tile_chart(meta, scenes, schedules, tiles, grid, name + ".png")
        except ImportError:
            print("charts_persist: no matplotlib (scripts/setup installs it): table only",
                  file=sys.stderr)
        print(name + ".md")
        return
    scenes, grid = cells(rows)
    if not any(BASE in g for g in grid.values()):
        sys.exit(f"{a.rows}: no weighted-megakernel rows to compare the persistent megakernel with")
    table(meta, scenes, grid, name + ".md")
    try:
        chart(meta, scenes, grid, name + ".png")
    except ImportError:
        print("charts_persist: no matplotlib (scripts/setup installs it): table only",
              file=sys.stderr)
    print(name + ".md")

