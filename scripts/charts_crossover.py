"""crossover.png: where does the wavefront win? (bench/sweeps/crossover), drawn by
charts.py; the numbers behind it for the generated README (readme_crossover.py).

The sweep's scenes are divergence-o<K>-m<M> (scripts/make-divergence.py): K noise octaves in
every procedural material (the shading cost), M distinct materials interleaved. Per setting
(scene, size, bounce limit) each pipeline's device time is divided by the best megakernel's
(the faster of its layouts that ran), and plotted against K, one panel per M. A ratio under 1
is a win over the megakernel; a star marks where a series first crosses under 1 (linear
interpolation between the two octave counts either side).
"""
import re
from collections import defaultdict

from chart_style import figure, legend_row, log_ticks, plt  # noqa: F401
from matplotlib.lines import Line2D
from sweep_rows import Series, failure, family, in_group

SCENE = re.compile(r"divergence-o(\d+)-m(\d+)$")
MEGA = "megakernel"  # the family every other series is divided by


def parse(r):
    """(octaves, materials) of a crossover row's scene, or None."""
    m = SCENE.search(r["scene"])
    return (int(m.group(1)), int(m.group(2))) if m else None


def crossover_rows(all_rows):
    return [r for r in in_group(all_rows, "crossover") if failure(r) == "" and parse(r)]


def ratios(rows):
    """{(series key, M, (w, h), B): [(K, ratio, row, best mega row)]} sorted by K, for every
    series that is not a megakernel, against the best megakernel at the same setting."""
    series = Series(rows)
    cells = defaultdict(dict)
    for r in rows:
        k, m = parse(r)
        cells[(m, (r["width"], r["height"]), r["bounces"], k)][series.key(r)] = r
    out = defaultdict(list)
    for (m, size, b, k), by in cells.items():
        megas = [r for key, r in by.items() if family(r) == MEGA]
        if not megas:
            continue
        best = min(megas, key=lambda r: r["device_ms"])
        for key, r in by.items():
            if family(r) != MEGA:
                out[(key, m, size, b)].append((k, r["device_ms"] / best["device_ms"], r, best))
    for v in out.values():
        v.sort(key=lambda t: t[0])
    return series, out


def crossing(points):
    """The octave count where the ratio first goes from >= 1 to < 1 (interpolated), 0.0 when it
    is under 1 from the start, None when it never is."""
    for i, (k, q, _, _) in enumerate(points):
        if q < 1:
            if i == 0:
                return 0.0
            k0, q0 = points[i - 1][0], points[i - 1][1]
            return k0 + (k - k0) * (q0 - 1) / (q0 - q)
    return None


def style_maps(keys):
    bounces = sorted({k[3] for k in keys})
    sizes = sorted({k[2] for k in keys})
    dashes = {b: s for b, s in zip(bounces, ["-", "--", ":", "-."] * 4)}
    markers = {s: m for s, m in zip(sizes, "osD^v")}
    return dashes, markers


def crossover_chart(meta, all_rows):
    rows = crossover_rows(all_rows)
    if not rows:
        return None
    series, data = ratios(rows)
    if not data:
        return None
    materials = sorted({k[1] for k in data})
    dashes, markers = style_maps(data.keys())
    fig, panels, legend_ax = figure(
        meta, f"Time over the best megakernel against material cost, {meta.get('device')}",
        len(materials), cols=3, legend_rows=2.0)
    for ax, m in zip(panels, materials):
        ax.axhline(1, color="black", linewidth=0.8)
        for key, pts in sorted(data.items()):
            if key[1] != m:
                continue
            x = [p[0] for p in pts]
            y = [p[1] for p in pts]
            ax.plot(x, y, color=series.color(key[0]), linestyle=dashes[key[3]],
                    marker=markers[key[2]], ms=3.5, linewidth=1.2)
            c = crossing(pts)
            if c is not None:
                ax.plot([c], [1], "*", color=series.color(key[0]), ms=12,
                        markeredgecolor="black", markeredgewidth=0.6, zorder=5)
        ax.set_yscale("log")
        log_ticks(ax)
        ax.set_title(f"{m} distinct material{'s' if m > 1 else ''}", fontsize=9)
        ax.set_xlabel("noise octaves per procedural material")
        ax.set_ylabel("device time / best megakernel")
        ax.grid(True, which="both", alpha=0.25)
    handles = [Line2D([], [], color=series.color(k), linewidth=2, label=series.label(k))
               for k in sorted({k[0] for k in data})]
    handles += [Line2D([], [], color="gray", linestyle=d, label=f"B={b}") for b, d in dashes.items()]
    handles += [Line2D([], [], color="gray", marker=mk, linestyle="", label=f"{s[0]}×{s[1]}")
                for s, mk in markers.items()]
    handles.append(Line2D([], [], color="gray", marker="*", linestyle="", ms=10,
                          label="crossover (ratio falls under 1)"))
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=5)
    return fig
