"""limits.png: how far each pipeline goes (bench/sweeps/limits), drawn by charts.py.

Per scene, a column per axis (bounce limit up at a fixed size, resolution up at a fixed bounce
limit) and three panels: device time, global memory and the longest launch. Filled circles ran,
squares ran with the global ray tree in K row tiles (K beside the memory point where there is
room), a dotted line and a cross on the top edge mark each series' first failure or first
setting not run. Everything a reader must decode (series, failures, the device's largest
allocation, the memory budget, max-launch-ms) is in the legend under each column, not on the
data. Series and failure kinds come from the rows (sweep_rows.limit_series), colours from
the palette in chart_style.py.
"""
from .chart_style import (DPI, footer_text, log_ticks, place_labels, plt,  # noqa: F401
                         point_boxes, resolution_axis, series_style)
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator
from matplotlib.transforms import offset_copy
from .sweep_rows import FAILURES_SHORT, in_group, limit_series, memory_tiles

PANELS = (("device ms per frame", lambda r: r["device_ms"]),
          ("global memory allocated, MiB", lambda r: r.get("device_bytes", 0) / 2**20),
          ("longest single launch, ms", lambda r: r.get("longest_launch_ms") or float("nan")))


def draw_series(axes, s, x):
    """One series' lines and markers in the three panels; returns the line for the legend."""
    style = dict(color=s["color"], linestyle=s["linestyle"])
    ran = s["ran"]
    tiled = [r for r in ran if memory_tiles(r) > 1]
    plain = [r for r in ran if memory_tiles(r) <= 1]
    line = None
    for ax, (_, val) in zip(axes, PANELS):
        drawn, = ax.plot([x(r) for r in ran], [val(r) for r in ran], linewidth=1.4, **style)
        line = line or drawn
        ax.plot([x(r) for r in plain], [val(r) for r in plain], "o", ms=4.5, color=s["color"])
        ax.plot([x(r) for r in tiled], [val(r) for r in tiled], "s", ms=6, color=s["color"],
                markeredgecolor="black", markeredgewidth=0.6)
    return line


def mark_stops(fig, axes, group, x, kind):
    """A dotted line through the panels and a cross on the top edge at each first failure;
    crosses at one x are set side by side. Returns legend (handle, label) pairs."""
    entries, at_x = [], {}
    stops = sorted((s for s in group if s["stop"] is not None), key=lambda s: x(s["stop"]))
    count = {}
    for s in stops:
        count[x(s["stop"])] = count.get(x(s["stop"]), 0) + 1
    for s in stops:
        sx = x(s["stop"])
        at_x[sx] = at_x.get(sx, -1) + 1
        n = at_x[sx] - (count[sx] - 1) / 2  # centred on the line
        for ax in axes:
            ax.axvline(sx, color=s["color"], linestyle=":", linewidth=1.0, alpha=0.8)
        shift = offset_copy(axes[0].get_xaxis_transform(), fig=fig, x=9 * n, units="points")
        axes[0].plot([sx], [1.0], marker="X", ms=9, color=s["color"], markeredgecolor="black",
                     markeredgewidth=0.6, transform=shift, clip_on=False)
        where = f"B={s['stop']['bounces']}" if kind == "bounces" else \
            f"{s['stop']['width']}×{s['stop']['height']}"
        entries.append((Line2D([], [], linestyle=":", marker="X", ms=8, color=s["color"],
                               markeredgecolor="black", markeredgewidth=0.6),
                        f"{s['label']}: first {'not run' if s['how'] == 'skipped' else 'failure'}"
                        f" {where}" + ("" if s["how"] == "skipped" else
                                       f" ({FAILURES_SHORT.get(s['how'], s['how'])})")))
    return entries


def reference_lines(axes, meta, group, limit_rows):
    """The device's largest allocation and any memory budget (memory panel), max-launch-ms
    (launch panel): horizontal lines named in the legend."""
    entries = []
    alloc = meta.get("max_alloc_bytes")
    if alloc:
        entries.append((axes[1].axhline(alloc / 2**20, color="#555555", linewidth=0.9,
                                        linestyle="--"),
                        f"device's largest allocation, {alloc / 2**30:.3g} GiB"))
    for b in sorted({s["budget"] for s in group if s.get("budget")}):
        entries.append((axes[1].axhline(b / 2**20, color="#b35900", linewidth=0.9, linestyle=":"),
                        f"memory budget {b / 2**20:g} MiB"))
    target = next((r.get("max_launch_ms") for r in limit_rows if r.get("max_launch_ms")), 0)
    if target:
        entries.append((axes[2].axhline(target, color="#555555", linewidth=0.9, linestyle="-."),
                        f"max-launch-ms {target:g} (longest launch panel)"))
    return entries


def label_tiles(fig, ax, group, x):
    """K beside the memory points of tiled frames, where there is room for it."""
    labels, points = [], []
    for s in group:
        for r in s["ran"]:
            points.append((x(r), r.get("device_bytes", 0) / 2**20))
            if memory_tiles(r) > 1:
                labels.append((x(r), r["device_bytes"] / 2**20, f"{memory_tiles(r)}", False))
    place_labels(fig, ax, labels, avoid=point_boxes(fig, ax, points, 3.5))


def limits_chart(meta, all_rows):
    series = limit_series(all_rows)
    if not series:
        return None
    for s in series:
        s["budget"] = s["rows"][0].get("memory_budget") or 0
        s.update(series_style(s["series"], s["key"]))  # the palette's colour, marker and line
    scenes = list(dict.fromkeys(s["scene"] for s in series))
    kinds = [k for k in ("bounces", "size") if any(s["axis"] == k for s in series)]
    ncol = len(kinds) * len(scenes)
    fig = plt.figure(figsize=(max(6.4 * ncol, 11), 13.5), layout="constrained", dpi=DPI)
    grid = fig.add_gridspec(4, ncol, height_ratios=[1, 1, 1, 0.7])
    limit_rows = in_group(all_rows, "limits")
    columns = []
    for col, (scene, kind) in enumerate((sc, k) for sc in scenes for k in kinds):
        axes = [fig.add_subplot(grid[i, col]) for i in range(3)]
        group = [s for s in series if s["scene"] == scene and s["axis"] == kind]
        if kind == "bounces":
            x = lambda r: r["bounces"]  # noqa: E731
            what = "bounce limit up"
        else:
            x = lambda r: r["width"] * r["height"] / 1e6  # noqa: E731
            what = "resolution up"
        fixed = ", ".join(sorted({s["fixed"][3:] for s in group}))
        axes[0].set_title(f"{scene}: {what} ({fixed})", fontsize=10, pad=12)
        entries = [(draw_series(axes, s, x), s["label"]) for s in group]
        entries += mark_stops(fig, axes, group, x, kind)
        entries += reference_lines(axes, meta, group, limit_rows)
        for ax, (ylabel, val) in zip(axes, PANELS):
            ax.set_ylabel(ylabel)
            if not any((val(r) or 0) > 0 for s in group for r in s["ran"]):
                # Rows from before a field was recorded: say so instead of a broken log axis.
                ax.text(0.5, 0.5, "not recorded by this sweep", transform=ax.transAxes,
                        ha="center", va="center", color="#555555")
            else:
                ax.set_yscale("log")
            ax.margins(x=0.04)
            ax.grid(True, which="both", alpha=0.25)
            if kind == "bounces":
                ax.xaxis.set_major_locator(MaxNLocator(integer=True))
                ax.set_xlabel("bounce limit B")
            else:
                resolution_axis(ax, [r for s in group for r in s["rows"]])
            log_ticks(ax)
        legend_ax = fig.add_subplot(grid[3, col])
        legend_ax.axis("off")
        legend = legend_ax.legend([h for h, _ in entries], [lab for _, lab in entries],
                                  loc="upper center", fontsize=7.5, ncol=1, frameon=False)
        legend.set_in_layout(False)  # a wide legend must not squeeze its column
        columns.append((axes[1], group, x))
    fig.suptitle("Limits: how far each pipeline goes\n"
                 "● ran   ■ ran with the global ray tree in "
                 "K row tiles (K beside the memory point)   ✕ on the top edge: first failure, or "
                 "first setting not run", fontsize=11)
    fig.supxlabel(footer_text(meta), fontsize=7, color="#555555")
    for ax, group, x in columns:
        label_tiles(fig, ax, group, x)
    return fig
