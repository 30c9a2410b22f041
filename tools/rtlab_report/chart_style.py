"""Figure scaffolding every result chart shares (charts.py, charts_limits.py,
charts_crossover.py, charts_map.py): the one palette (a fixed colour and marker per pipeline and
layout), the footer that names device, driver, commit and timing, a row under the panels that
holds the legend (so that no legend covers data), log axes labelled in one style, labels that
must not overlap, and how a missing cell is marked.
Needs Debian's python3-matplotlib (scripts/setup).
"""
import colorsys
import math
import textwrap
import zlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.transforms import Bbox
from .sweep_rows import own_options
from matplotlib.ticker import (FixedLocator, FuncFormatter, MaxNLocator,
                               NullFormatter, NullLocator)


DPI = 110
MARKERS = "osD^v<>p*h"

# The palette: one colour and marker per series, the same in every chart, keyed by pipeline and,
# for pipelines with a ray-storage layout, the layout. Okabe-Ito colours, which stay apart for
# colour-blind readers; the megakernel family in blues and greens, the wavefronts in warm hues.
SERIES_STYLES = {
    ("mega", "tree"): ("#0072B2", "o"),       # blue
    ("mega", "weighted"): ("#009E73", "s"),   # bluish green
    ("persist", None): ("#56B4E9", "v"),      # sky blue
    ("wave", None): ("#D55E00", "^"),         # vermillion
    ("queue", None): ("#CC79A7", "D"),        # reddish purple
    ("auto", None): ("#E69F00", "P"),         # orange
    ("cpu", None): ("#000000", "X"),          # black: the CPU reference
}

# One design's variants (the persistent megakernel's schedules, tile orders), where a chart
# shows several side by side: shades of the design's own colour family, none of them another
# design's colour, so that a colour never names two designs across the charts.
VARIANT_SHADES = {
    "persist": ["#56B4E9", "#8fd3f5", "#2a9fd6", "#b9e3f7", "#3c7fb1", "#7fb8da", "#1a5a88",
                "#a9c6de", "#5e9cc9", "#d4ecf9", "#28688f", "#93cbea", "#4aa3d8", "#c3d8ea"],
}


def design_color(pipeline, layout=None):
    """The palette's colour of a design, by pipeline (and the megakernel's layout)."""
    return (SERIES_STYLES.get((pipeline, layout)) or SERIES_STYLES[(pipeline, None)])[0]


def variant_color(pipeline, i):
    """The i-th variant's colour of one design (VARIANT_SHADES), its own colour first."""
    shades = VARIANT_SHADES.get(pipeline) or [design_color(pipeline)]
    return shades[i % len(shades)]


# Pipelines not listed above: a colour none of them uses, picked by a stable hash of the name.
OTHER_COLORS = ["#8c564b", "#7f7f7f", "#bcbd22", "#17becf", "#9467bd"]
OTHER_MARKERS = "<>ph*"
LINESTYLES = ["-", "--", ":", "-."]
MISSING_MARKER = "x"  # a cell that did not run, drawn where its point would be
TIE_COLOR = "#dddddd"  # a setting without a winner beyond the frame spread


def base_style(row):
    """(colour, marker) of the series a row belongs to."""
    layout = own_options(row).get("layout")
    found = SERIES_STYLES.get((row["pipeline"], layout)) or SERIES_STYLES.get((row["pipeline"], None))
    if found:
        return found
    slot = zlib.crc32(row["pipeline"].encode()) % len(OTHER_COLORS)
    return OTHER_COLORS[slot], OTHER_MARKERS[slot]


def series_style(series, key):
    """{color, marker, linestyle} of a series key (sweep_rows.Series): the palette's colour and
    marker, and a line style that tells apart the keys sharing them (memory budgets, other
    options of one pipeline), solid for the first."""
    color, marker = base_style(series.first[key])
    same = [k for k in series.keys if base_style(series.first[k]) == (color, marker)]
    return {"color": color, "marker": marker,
            "linestyle": LINESTYLES[same.index(key) % len(LINESTYLES)]}


# Lightness of the keys after the first that share a palette colour, where a chart fills areas
# and a line style cannot tell them apart (the map's cells): darker, lighter, and so on.
SHADES = [1.0, 0.6, 1.3, 0.42, 1.45]


def series_fill(series, key):
    """A fill colour of a series key: its palette colour, darkened or lightened for each further
    key that shares it (several schedules of one pipeline on one map)."""
    color, marker = base_style(series.first[key])
    same = [k for k in series.keys if base_style(series.first[k]) == (color, marker)]
    h, l, s = colorsys.rgb_to_hls(*matplotlib.colors.to_rgb(color))
    shaded = colorsys.hls_to_rgb(h, min(0.88, l * SHADES[same.index(key) % len(SHADES)]), s)
    return matplotlib.colors.to_hex(shaded)


def text_on(fill):
    """Black or white, whichever reads better on a fill colour."""
    r, g, b = matplotlib.colors.to_rgb(fill)
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.6 else "white"


def footer_text(meta):
    s = meta.get("settings", {})
    return (f"{meta.get('device')} | {meta.get('platform')}, driver {meta.get('driver')} | "
            f"commit {meta.get('commit')} | sweep {meta.get('sweep')}\ndevice time = sum of the "
            f"frame's kernels by OpenCL profiling events, median of {s.get('repeats')} frames "
            f"after {s.get('warmup')} warm-up")


def figure(meta, title, n, cols=3, panel=(4.6, 3.6), legend_rows=1.0):
    """A figure with n panels in a grid and, below them, one axis-less row for the legend.
    Constrained layout leaves the room the title, the legend and the footer need, no more.
    Returns (fig, panels, legend axis)."""
    cols = min(cols, max(1, n))
    rows = max(1, math.ceil(n / cols))
    width = max(panel[0] * cols, 9)
    # dpi as saved, so that text boxes measured after a draw are the saved ones.
    fig = plt.figure(figsize=(width, panel[1] * rows + 0.45 * legend_rows + 0.9),
                     layout="constrained", dpi=DPI)
    gs = fig.add_gridspec(rows + 1, cols,
                          height_ratios=[panel[1]] * rows + [0.45 * legend_rows])
    panels = [fig.add_subplot(gs[i // cols, i % cols]) for i in range(n)]
    legend_ax = fig.add_subplot(gs[rows, :])
    legend_ax.axis("off")
    # Each line of the title wrapped to the figure's width (about 12 characters an inch at 11
    # points), so that a long note cannot run off both edges and squash the panels.
    per_line = max(40, int(width * 12))
    fig.suptitle("\n".join(textwrap.fill(line, per_line) for line in title.split("\n")),
                 fontsize=11)
    fig.supxlabel(footer_text(meta), fontsize=7, color="#555555")
    return fig, panels, legend_ax


def legend_columns(width, labels, ncol):
    """No more legend columns than a figure `width` inches wide holds for its longest label
    (about 0.058 in a character at 8 points, plus the marker): a wider legend is cut off."""
    longest = max((len(lab) for lab in labels), default=1)
    return max(1, min(ncol, len(labels), int(width / (0.058 * longest + 0.5))))


def legend_height(width, labels, ncol):
    """figure()'s legend_rows for a legend of these labels: about 0.22 in a line of entries at
    8 points, and room for a line of text above them."""
    rows = math.ceil(len(set(labels)) / legend_columns(width, list(set(labels)), ncol))
    return (0.22 * rows + 0.35) / 0.45


def legend_row(legend_ax, handles, labels, ncol=None):
    """The figure's legend in its own row: one entry per label."""
    seen = {}
    for h, lab in zip(handles, labels):
        seen.setdefault(lab, h)
    if not seen:
        return None
    ncol = legend_columns(legend_ax.figure.get_figwidth(), list(seen), ncol or min(len(seen), 4))
    return legend_ax.legend(list(seen.values()), list(seen.keys()), loc="center", ncol=ncol,
                            fontsize=8, frameon=False)


def plain(v, _pos=None):
    return f"{v:g}"


def log_ticks(ax, which="y"):
    """A log axis labelled in plain numbers (0.1, 1, 10) in one style, so that `90, 10^2, 110`
    cannot happen, and with at least three labels (matplotlib may give a short axis one).
    Past 6 decades matplotlib's 10^n labels stay."""
    axis = ax.yaxis if which == "y" else ax.xaxis
    lo, hi = ax.get_ylim() if which == "y" else ax.get_xlim()
    if lo <= 0 or hi / lo >= 1e6:
        return
    decades = range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
    ticks = []
    # The coarsest set of round numbers that puts at least three labels on the axis.
    for subs in ((1,), (1, 2, 5), (1, 1.5, 2, 3, 5, 7), (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 7, 8, 9)):
        ticks = [m * 10.0**k for k in decades for m in subs if lo <= m * 10.0**k <= hi]
        if len(ticks) >= 3:
            break
    else:  # under ~a third of a decade: evenly spaced round numbers
        ticks = [t for t in MaxNLocator(nbins=5).tick_values(lo, hi) if lo <= t <= hi]
    axis.set_major_locator(FixedLocator(ticks))
    axis.set_major_formatter(FuncFormatter(plain))
    axis.set_minor_formatter(NullFormatter())


def boxes_overlap(a, b, pad=1.0):
    return not (a.x1 + pad <= b.x0 or b.x1 + pad <= a.x0 or
                a.y1 + pad <= b.y0 or b.y1 + pad <= a.y0)


def point_boxes(fig, ax, points, radius_pt):
    """Display boxes of markers at data points (x, y), radius in points."""
    r = radius_pt * fig.dpi / 72
    out = []
    for x, y in points:
        px, py = ax.transData.transform((x, y))
        out.append(Bbox([[px - r, py - r], [px + r, py + r]]))
    return out


def place_labels(fig, ax, labels, avoid=()):
    """Annotates (x, y, text, keep) points so that no two labels overlap, none covers a box of
    `avoid` (markers, from point_boxes) and none leaves the axes: each tries four positions
    around its point and is left out when none fits. Returns the texts placed."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    placed, boxes = [], []
    offsets = [((6, 5), "left", "bottom"), ((6, -5), "left", "top"),
               ((-6, 5), "right", "bottom"), ((-6, -5), "right", "top")]
    for x, y, text, keep in labels:
        for (dx, dy), ha, va in offsets:
            t = ax.annotate(text, (x, y), textcoords="offset points", xytext=(dx, dy),
                            fontsize=6.5, ha=ha, va=va)
            t.set_in_layout(False)  # placed last: must not move the panels it was measured in
            box = t.get_window_extent(renderer)
            inside = (box.x0 >= frame.x0 and box.x1 <= frame.x1 and box.y0 >= frame.y0 and
                      box.y1 <= frame.y1)
            # Labels 4 px apart at least: two that touch read as one (`B1 s1 aa1B4 s4 aa1`).
            if inside and not any(boxes_overlap(box, o, pad=4.0) for o in boxes) and \
                    not any(boxes_overlap(box, o, pad=0.0) for o in avoid):
                boxes.append(box)
                placed.append(t)
                break
            t.remove()
        else:
            if keep:
                print(f"charts: label {text!r} left out: no free place beside its point")
    return placed


def resolution_axis(ax, rows):
    """A log megapixel axis ticked at the resolutions measured, labelled W×H."""
    sizes = sorted({(r["width"], r["height"]) for r in rows}, key=lambda wh: wh[0] * wh[1])
    ax.set_xscale("log")
    ax.set_xticks([w * h / 1e6 for w, h in sizes])
    ax.set_xticklabels([f"{w}×{h}" for w, h in sizes], fontsize=7, rotation=30)
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xlabel("resolution (log of pixels)")
