"""Draws the crossover map of a `map` sweep (bench/sweeps/map, scenes of scripts/make-map.py):
which design is fastest at each (sphere size on screen, share of mirrors and glass), one panel per
shading cost (and per triangle count of the mesh walls of bench/sweeps/map-mesh), the cell
coloured by the winner and labelled with its margin over the runner-up. A margin inside the
measured frame spread (compare.py's tie rule: the medians no further apart than the larger of the
two cells' spreads) is a tie, drawn hatched and labelled "tie". A setting where some design did
not run is marked
missing: wins are counted only where every design ran. Also writes a Markdown table beside the
chart with every time, the winner, the margin and the megakernel's busy lanes per warp where
the rows carry them.

Usage: python3 -m rtlab_report map-charts ROWS.jsonl|SWEEP.json... [--out DIR]
  (the rows of `rtlab-bench --sweep map`, `map-dense` or `map-mesh`, or the JSON `rtlab sweep` writes; several
  files are drawn as one map, the first one's meta naming device, driver and commit)
Needs Debian's python3-matplotlib for the chart; the table needs nothing.
"""
import argparse
import json
import os
import re
import sys

from .compare import Verdict
from .sweep_rows import Series, family, own_options

NAME = re.compile(r"map-s(\d+)(?:-t(\d+))?-x(\d+)-o(\d+)-m(\d+)(?:-f\d+x\d+)?$")


def load(path):
    if path.endswith(".jsonl"):
        with open(path) as f:
            rows = [json.loads(line) for line in f if line.strip()]
        meta_path = os.path.join(os.path.dirname(path), "sweep.json")
        if os.path.exists(meta_path):
            return json.load(open(meta_path)), rows
        # Rows that came back without their sweep's JSON (a cut-short device call) still say
        # where and at which commit they ran.
        first = rows[0] if rows else {}
        meta = {k: first[k] for k in ("device", "platform", "driver", "commit", "sweep")
                if k in first}
        meta["settings"] = {k: first[k] for k in ("repeats", "warmup") if k in first}
        return meta, rows
    data = json.load(open(path))
    return data["meta"], data["rows"]


def cells(rows):
    """{(size, special, octaves, materials, triangles): {series key: row}} for the map's scenes;
    triangles is the mesh walls' count an object, 0 for spheres."""
    # A selector (`--pipeline auto`) renders with one of the designs on the map: it is no
    # contender of its own (tools/rtlab_report/auto_eval.py sets it against them).
    rows = [r for r in rows if family(r) != "selector"]
    series = Series(rows)
    out = {}
    for r in rows:
        m = NAME.search(r["scene"])
        if not m:
            continue
        size, triangles, special, octaves, materials = (int(g or 0) for g in m.groups())
        out.setdefault((size, special, octaves, materials, triangles), {})[series.key(r)] = r
    return series, out


def verdict(by_key, keys):
    """(fastest, runner-up, margin, tie) among rows that ran, or None when one did not. tie:
    the fastest ties another design by compare.py's rule (medians no further apart than the
    larger frame spread)."""
    ran = {k: r for k, r in by_key.items() if r.get("status") == "ok"}
    if any(k not in ran for k in keys):
        return None
    v = Verdict(ran)
    return v.fastest, v.runner, v.margin, v.is_tie


def table(meta, series, grid, keys, path):
    lines = [f"# Crossover map: {meta.get('device', '?')} (driver {meta.get('driver', '?')}, "
             f"commit {meta.get('commit', '?')})", "",
             "Device time of a frame (median of the timed frames, ms); the "
             "winner's margin is the runner-up's time over the winner's, a tie when the medians "
             "differ by no more than the larger of the two cells' frame spreads (tools/rtlab_report/compare.py). In "
             "brackets after a megakernel's time: its mean busy lanes of a 32-lane warp over the "
             "steps of its ray loop (counted on NVIDIA only).", ""]
    mesh = any(g[4] for g in grid)  # a triangles column only for mesh walls
    head = "| size px | " + ("triangles | " if mesh else "") + "mirrors+glass | octaves | " + \
           " | ".join(series.label(k) for k in keys) + " | winner | margin |"
    lines += [head, "|" + "---|" * (head.count("|") - 1)]
    wins, settings = {}, 0
    for (size, special, octaves, materials, triangles) in sorted(grid):
        by_key = grid[(size, special, octaves, materials, triangles)]
        v = verdict(by_key, keys)
        times = []
        for k in keys:
            r = by_key.get(k)
            if not r or r.get("status") != "ok":
                times.append("missing")
                continue
            lanes = r.get("extras", {}).get("warp_lanes_active")
            times.append(f"{r['device_ms']:.3f}" + (f" ({lanes:.1f})" if lanes is not None else ""))
        if v:
            settings += 1
            winner, _, margin, tie = v
            wins[("tie" if tie else winner)] = wins.get("tie" if tie else winner, 0) + 1
            who, by = ("tie", f"{margin:.2f} (in spread)") if tie else (series.label(winner), f"{margin:.2f}x")
        else:
            who, by = "not all ran", "-"
        lines.append(f"| {size} | " + (f"{triangles} | " if mesh else "") +
                     f"{special}% | {octaves} | " + " | ".join(times) +
                     f" | {who} | {by} |")
    lines += ["", f"Settings where every design ran: {settings}. Wins there: " +
              ", ".join(f"{series.label(k) if k != 'tie' else 'ties'} {n}"
                        for k, n in sorted(wins.items(), key=lambda kv: -kv[1])) + "."]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def chart(meta, series, grid, keys, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch
    from .chart_style import TIE_COLOR, figure, legend_row, series_fill, text_on

    # A panel per (triangles an object, octaves): one per shading cost on the sphere map.
    kinds = sorted({(g[4], g[2]) for g in grid})
    won = set()
    r0 = next(iter(next(iter(grid.values())).values()))
    fig, panels, legend_ax = figure(meta, "Fastest design per setting and its margin over the "
                                    f"runner-up ({r0['width']}x{r0['height']}, B = {r0['bounces']})",
                                    len(kinds), cols=len(kinds), panel=(4.8, 3.9))
    for ax, (t, o) in zip(panels, kinds):
        # Each panel spans the sizes and shares measured at its cost and triangle count.
        sizes = sorted({g[0] for g in grid if (g[4], g[2]) == (t, o)})
        specials = sorted({g[1] for g in grid if (g[4], g[2]) == (t, o)})
        ax.set_xlim(-0.5, len(sizes) - 0.5)
        ax.set_ylim(-0.5, len(specials) - 0.5)
        for i, s in enumerate(sizes):
            for j, x in enumerate(specials):
                found = [g for g in grid if g[:3] == (s, x, o) and g[4] == t]
                v = verdict(grid[found[0]], keys) if found else None
                if v is None:
                    ax.add_patch(plt.Rectangle((i - 0.5, j - 0.5), 1, 1, facecolor="white",
                                               edgecolor="#999999", hatch="xx"))
                    ax.text(i, j, "missing", ha="center", va="center", fontsize=7, color="#555555")
                    continue
                winner, runner, margin, tie = v
                fill = TIE_COLOR if tie else series_fill(series, winner)
                won.add(winner)
                ax.add_patch(plt.Rectangle((i - 0.5, j - 0.5), 1, 1, facecolor=fill,
                                           edgecolor="white", hatch="//" if tie else None))
                text = "tie" if tie else f"{margin:.2f}x"
                ax.text(i, j + (0.12 if tie else 0), text, ha="center", va="center", fontsize=9,
                        color="black" if tie else text_on(fill), fontweight="bold")
                if tie:
                    # Which two tie: the fastest and the runner-up, by short name.
                    ax.text(i, j - 0.18, f"{short_name(series, winner)} ~\n"
                            f"{short_name(series, runner)}", ha="center", va="center",
                            fontsize=6.5, color="#333333", linespacing=0.95)
        ax.set_xticks(range(len(sizes)), [f"{s} px" for s in sizes])
        ax.set_yticks(range(len(specials)), [f"{x}%" for x in specials])
        ax.set_xlabel("icosphere size on screen" if t else "sphere size on screen")
        ax.set_ylabel("mirrors and glass")
        ax.set_title(f"{t} triangles an object, {o} octaves" if t else f"{o} noise octaves",
                     fontsize=10)
    # Only the designs that fill a cell; the others are named as never the fastest.
    handles = [Patch(facecolor=series_fill(series, k), label=series.label(k))
               for k in keys if k in won]
    handles.append(Patch(facecolor=TIE_COLOR, hatch="//", label="tie (inside the frame spread): "
                         "the two fastest named"))
    never = [series.label(k) for k in keys if k not in won]
    if never:
        handles.append(Patch(facecolor="white", edgecolor="#999999",
                             label="measured, never the fastest: " + "; ".join(never)))
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=len(handles))
    fig.savefig(path)
    plt.close(fig)


SHORT = {"mega": "mega", "persist": "persist", "wave": "tree wave", "queue": "queue",
         "auto": "auto"}


def short_name(series, key):
    """A design's name short enough for a cell: the pipeline, and the megakernel's layout."""
    r = series.first[key]
    name = SHORT.get(r["pipeline"], r["pipeline"])
    layout = own_options(r).get("layout")
    return f"{name} ({layout})" if r["pipeline"] == "mega" and layout else name


def commits_of(meta, rows):
    """The commit the chart names: the one the rows record, every one of them (short, in order of
    first appearance) when a map joins runs of several binaries (a sweep resumed at another
    commit), or the meta's when the rows record none."""
    seen = []
    for r in rows:
        c = (r.get("commit") or "")[:12]
        if c and c not in seen:
            seen.append(c)
    if len(seen) > 1:
        return ", ".join(c[:7] for c in seen)
    return seen[0] if seen else meta.get("commit", "?")


def drop_rows(rows, drops):
    """The rows whose fields match none of the FIELD=VALUE strings in `drops` (values compared as
    text, so that persistent_groups=2 matches the number 2)."""
    pairs = []
    for d in drops:
        field, sep, value = d.partition("=")
        if not sep or not field:
            sys.exit(f"--drop {d}: expected FIELD=VALUE")
        pairs.append((field, value))
    return [r for r in rows if not any(str(r.get(f)) == v for f, v in pairs)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rows", nargs="+")
    ap.add_argument("--out", default=None, help="folder for map.png and map.md [beside the first]")
    ap.add_argument("--drop", action="append", default=[], metavar="FIELD=VALUE",
                    help="leave out the rows whose FIELD is VALUE (persistent_schedule=auto); "
                         "repeat for more")
    a = ap.parse_args(argv)
    meta, rows = load(a.rows[0])
    for more in a.rows[1:]:
        rows += load(more)[1]
    rows = drop_rows(rows, a.drop)
    meta = dict(meta, commit=commits_of(meta, rows))
    series, grid = cells(rows)
    if not grid:
        sys.exit(f"{' '.join(a.rows)}: no rows of map scenes "
                 "(map-s<size>[-t<triangles>]-x<share>-o<octaves>-m<materials>)")
    keys = series.keys
    out = a.out or os.path.dirname(os.path.abspath(a.rows[0]))
    os.makedirs(out, exist_ok=True)
    table(meta, series, grid, keys, os.path.join(out, "map.md"))
    try:
        chart(meta, series, grid, keys, os.path.join(out, "map.png"))
    except ImportError:
        print("charts_map: no matplotlib (scripts/setup installs it): table only", file=sys.stderr)
    print(os.path.join(out, "map.md"))

