"""crossover.png: where does the wavefront win? (bench/sweeps/crossover), drawn by
charts.py; the numbers behind it for the generated README (readme_crossover.py).

The sweep's scenes are divergence-o<K>-m<M> (scripts/make-divergence.py): K noise octaves in
every procedural material (the shading cost), M distinct materials interleaved. Per setting
(scene, size, bounce limit) each pipeline's device time is divided by the best megakernel's
(the faster of its layouts that ran), and plotted against K, one panel per M, each point with
its frame spread. A ratio under 1 is a win over the megakernel only beyond the frame spread
(compare.py); a tie is drawn hollow, and a star marks the first measured octave count where a
series wins beyond the spread (never a point interpolated between two measurements). Every panel
has the same y range, so that panels compare at a glance; the legend lists only what is drawn.
"""
from .chart_style import figure, legend_row, log_ticks, series_style
from matplotlib.lines import Line2D
from .compare import spread
from .readme_crossover import crossing, crossover_rows, outcome, ratios

def style_maps(keys):
    """Line style per bounce limit, marker size per frame size (at most three sizes)."""
    bounces = sorted({k[3] for k in keys})
    sizes = sorted({k[2] for k in keys}, key=lambda wh: wh[0] * wh[1])
    dashes = {b: d for b, d in zip(bounces, ["-", "--", ":", "-."] * 4)}
    marks = {s: m for s, m in zip(sizes, (3.5, 5.5, 7.5) if len(sizes) > 1 else (5,))}
    return dashes, marks


def crossover_chart(meta, all_rows):
    rows = crossover_rows(all_rows)
    if not rows:
        return None
    series, data = ratios(rows)
    if not data:
        return None
    materials = sorted({k[1] for k in data})
    dashes, marks = style_maps(data.keys())
    fig, panels, legend_ax = figure(
        meta, f"Time over the best megakernel against material cost, {meta.get('device')}\n"
        "filled: a win or loss beyond the frame spread; hollow: a tie (tools/rtlab_report/compare.py)",
        len(materials), cols=3, legend_rows=2.4)
    drew_tie = drew_star = False
    # Series drawn a little apart in x (a fraction of the octave axis), so that two points of
    # one setting never overprint; the ticks stay at the measured octave counts.
    names = sorted({k[0] for k in data})
    width = max(k for pts in data.values() for k, *_ in pts) or 1
    dodge = {n: (i - (len(names) - 1) / 2) * 0.012 * width for i, n in enumerate(names)}
    for ax, m in zip(panels, materials):
        ax.axhline(1, color="black", linewidth=0.8)
        for key, pts in sorted(data.items()):
            if key[1] != m:
                continue
            st = series_style(series, key[0])
            x = [p[0] + dodge[key[0]] for p in pts]
            y = [p[1] for p in pts]
            # The ratio's bar: the series cell's fastest and slowest frame over the best
            # megakernel's median.
            lo = [p[1] - spread(p[2])[0] / p[3]["device_ms"] for p in pts]
            hi = [spread(p[2])[1] / p[3]["device_ms"] - p[1] for p in pts]
            ax.errorbar(x, y, yerr=[lo, hi], color=st["color"], linestyle=dashes[key[3]],
                        linewidth=1.1, elinewidth=0.6, capsize=1.5)
            for p in pts:
                tie = outcome(p) == "tie"
                drew_tie |= tie
                ax.plot([p[0] + dodge[key[0]]], [p[1]], st["marker"], ms=marks[key[2]],
                        color=st["color"],
                        markerfacecolor="white" if tie else st["color"], zorder=4)
            c = crossing(pts)
            if c is not None:
                drew_star = True
                ax.plot([c + dodge[key[0]]], [next(p[1] for p in pts if p[0] == c)], "*",
                        color=st["color"],
                        ms=13, markeredgecolor="black", markeredgewidth=0.6, zorder=5)
        ax.set_yscale("log")
        log_ticks(ax)
        ax.set_title(f"{m} distinct material{'s' if m > 1 else ''}", fontsize=9)
        ax.set_xlabel("noise octaves per procedural material")
        ax.set_ylabel("device time / best megakernel")
        ax.grid(True, which="both", alpha=0.25)
    # One y range for every panel (log axis: the union of their ranges).
    lo = min(ax.get_ylim()[0] for ax in panels)
    hi = max(ax.get_ylim()[1] for ax in panels)
    for ax in panels:
        ax.set_ylim(lo, hi)
        log_ticks(ax)
    handles = []
    for k in sorted({k[0] for k in data}):
        st = series_style(series, k)
        handles.append(Line2D([], [], color=st["color"], marker=st["marker"], linewidth=2,
                              label=series.label(k)))
    handles += [Line2D([], [], color="gray", linestyle=d, label=f"B={b}") for b, d in dashes.items()]
    handles += [Line2D([], [], color="gray", marker="o", ms=ms, linestyle="",
                       label=f"{s[0]}×{s[1]}") for s, ms in marks.items()]
    if drew_tie:
        handles.append(Line2D([], [], color="gray", marker="o", markerfacecolor="white",
                              linestyle="", label="tie with the best megakernel"))
    if drew_star:
        handles.append(Line2D([], [], color="gray", marker="*", linestyle="", ms=10,
                              label="crossover: first octave count with a win beyond the spread"))
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=4)
    return fig
