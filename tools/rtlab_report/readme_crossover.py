"""The generated README's Crossover section (bench/sweeps/crossover): per pipeline its
time over the best megakernel against material cost and material count, where it first wins,
and why, measured: the kernels' registers and spills (NVIDIA build log) or private bytes per
work-item, and each wavefront stage's share of device time. Used by results_readme.py; the
ratios and crossings are also what charts_crossover.py draws.

The sweep's scenes are divergence-o<K>-m<M> (scripts/make-divergence.py): K noise octaves in
every procedural material, M distinct materials interleaved. Per setting (scene, size, bounce
limit) each other pipeline's device time is divided by the best megakernel's (the faster of its
layouts that ran). A ratio under 1 is a win only when the two cells do not tie (compare.py):
a crossover is the first measured octave count with a win beyond the frame spread, never a
point interpolated between two measurements.
Standard library only.
"""
import math
import re
from collections import defaultdict

from .compare import relative_spread, tied
from .readme_format import table
from .sweep_rows import Series, failure, family, in_group

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


def outcome(point):
    """'win', 'tie' or 'loss' of one (K, ratio, row, best mega row) against the best megakernel."""
    _, q, r, best = point
    if tied(r, best):
        return "tie"
    return "win" if q < 1 else "loss"


def crossing(points):
    """The first measured octave count at which the series wins beyond the frame spread
    (compare.py), None when it never does. No interpolation: between two measurements nothing
    was measured, and a point inside the spread is a tie, not a crossover."""
    for p in points:
        if outcome(p) == "win":
            return p[0]
    return None


# The kernels whose cost the question turns on: the megakernel, the tree wavefront's trace, the
# queue's extend and its costliest shade kernels.
KERNELS = {"Megakernel_Render", "Wavefront_Trace", "Queue_Extend", "Queue_ShadeProcedural",
           "Queue_ShadeGlass"}


def geo(v):
    return math.exp(sum(math.log(x) for x in v) / len(v))


def size_text(s):
    return f"{s[0]}×{s[1]}"


def ratio_table(series, data):
    """Rows (M, K), a column per series: geometric mean over sizes and bounce limits (range)."""
    keys = sorted({k[0] for k in data})
    by = defaultdict(lambda: defaultdict(list))
    for (key, m, _, _), pts in data.items():
        for k, q, _, _ in pts:
            by[(m, k)][key].append(q)
    body = []
    for (m, k) in sorted(by):
        body.append([m, k] + [f"{geo(v):.2f} ({min(v):.2f} – {max(v):.2f})" if (v := by[(m, k)][s])
                              else "–" for s in keys])
    return table(["Materials M", "Octaves K"] + [series.label(s) + " / best mega" for s in keys],
                 body)


def crossing_lines(series, data):
    """One line per series: how often it beats, ties and loses to the best megakernel, its best
    ratio, and where it first wins beyond the spread, or that it never does."""
    lines = []
    top = max(p[0] for pts in data.values() for p in pts)
    for key in sorted({k[0] for k in data}):
        mine = {k: v for k, v in data.items() if k[0] == key}
        best = min(((p[1], k, p) for k, pts in mine.items() for p in pts), key=lambda t: t[0])
        found = []
        for (_, m, size, b), pts in sorted(mine.items(), key=lambda t: t[0][1:]):
            c = crossing(pts)
            if c is not None:
                found.append(f"M={m} {size_text(size)} B={b}: "
                             + ("wins from K=0" if c == pts[0][0] else f"first wins at K={c}"))
        every = [p for pts in mine.values() for p in pts]
        count = {o: sum(1 for p in every if outcome(p) == o) for o in ("win", "tie", "loss")}
        ratio, where, point = best
        level = " (a tie: within the frame spread)" if outcome(point) == "tie" else ""
        text = (f"- **{series.label(key)}**: faster than the best megakernel beyond the frame "
                f"spread in {count['win']} of {len(every)} settings, tied in {count['tie']}, "
                f"slower in {count['loss']}; lowest ratio {ratio:.2f}{level} (M={where[1]}, "
                f"K={point[0]}, {size_text(where[2])}, B={where[3]}). ")
        text += ("Crossovers (first measured octave count with a win beyond the spread): "
                 + "; ".join(found) + "." if found else
                 f"No crossover up to the largest cost tried (K = {top} octaves).")
        lines.append(text)
    return lines


def resource_table(rows):
    """Per pipeline (layout), material count and bounce limit: each kernel's registers, spill
    bytes (stores/loads) and private bytes per work-item, as the rows recorded them."""
    seen = {}
    series = Series(rows)
    for r in rows:
        res = r.get("kernel_resources") or {}
        k, m = parse(r)
        pipe = series.label(series.key(r))
        kernels = sorted({name.split(".")[0] for name in res} & KERNELS)
        for kern in kernels:
            seen.setdefault((pipe, m, r["bounces"], kern), res)
    body = []
    for (pipe, m, b, kern), res in sorted(seen.items()):
        def val(f):
            v = res.get(f"{kern}.{f}")
            return "–" if v is None else f"{v:g}"
        body.append([pipe, m, b, kern, val("registers"),
                     f"{val('spill_stores')}/{val('spill_loads')}", val("private_bytes")])
    if not body:
        return ""
    return table(["Pipeline", "M", "B", "Kernel", "Registers", "Spill bytes st/ld",
                  "Private bytes"], body)


def stage_table(rows):
    """Per wavefront pipeline and material count, at the least and most octaves: each stage's
    share of device time, summed over sizes and bounce limits (stages under 2% left out)."""
    sums = defaultdict(lambda: defaultdict(float))
    octs = defaultdict(set)
    for r in rows:
        if family(r) == "megakernel":
            continue
        k, m = parse(r)
        octs[(r["pipeline"], m)].add(k)
        for name, ms in (r.get("kernel_ms") or {}).items():
            sums[(r["pipeline"], m, k)][name] += ms
    body = []
    for (pipe, m), ks in sorted(octs.items()):
        for k in sorted({min(ks), max(ks)}):
            s = sums[(pipe, m, k)]
            total = sum(s.values()) or 1
            parts = sorted(s.items(), key=lambda t: -t[1])
            body.append([pipe, m, k, ", ".join(f"{n} {100 * v / total:.0f}%"
                                                for n, v in parts if v / total >= 0.02)])
    return table(["Pipeline", "M", "K", "Share of device time per stage"], body) if body else ""


def mega_cost_line(rows):
    """How much of the best megakernel's time the noise adds: its time at the most octaves over
    its time at none, geometric mean over the settings."""
    best = defaultdict(dict)
    for r in rows:
        if family(r) != "megakernel":
            continue
        k, m = parse(r)
        key = (m, r["width"], r["height"], r["bounces"])
        best[key][k] = min(best[key].get(k, math.inf), r["device_ms"])
    q = [v[max(v)] / v[min(v)] for v in best.values() if len(v) > 1 and v[min(v)] > 0]
    if not q:
        return ""
    kmin = min(min(v) for v in best.values())
    kmax = max(max(v) for v in best.values())
    return (f"The best megakernel takes {geo(q):.2f}× as long at K={kmax} as at K={kmin} "
            f"(geometric mean over the settings, range {min(q):.2f} – {max(q):.2f}): "
            f"{100 * (1 - 1 / geo(q)):.0f}% of its time at K={kmax} is the noise.")


def noise_line(rows):
    """How far one cell's timed frames spread, as a reminder of what the ties above mean."""
    spreads = sorted(relative_spread(r) for r in rows if r.get("device_ms"))
    if not spreads:
        return ""
    mid = spreads[len(spreads) // 2]
    return (f"Noise: the timed frames of one cell spread by {100 * mid:.0f}% of its median "
            f"(median over the cells; max − min); a ratio whose two cells differ by less than "
            "the larger of their spreads is counted as a tie above, not a win.")


def crossover_section(data, json_rel, chart_exists):
    meta, all_rows = data["meta"], data["rows"]
    rows = crossover_rows(all_rows)
    if not rows:
        return []
    series, ratio = ratios(rows)
    doc = ["## Crossover: where does the wavefront win?",
           "",
           f"From [`{json_rel}`]({json_rel}) (sweep `{meta.get('config_file')}`, commit "
           f"`{meta.get('commit')}`). Scenes `divergence-o<K>-m<M>` (scripts/make-divergence.py): "
           "K noise octaves in every procedural material, M distinct materials interleaved "
           "(scenes/README.md). Ratio: a pipeline's device time over the faster megakernel "
           "layout's at the same setting; under 1, the wavefront wins.",
           ""]
    if chart_exists:
        doc += ["![Time over the best megakernel against material cost](crossover.png)", ""]
    doc += crossing_lines(series, ratio) + [""]
    spread = noise_line(rows)
    if spread:
        doc += [spread, ""]
    line = mega_cost_line(rows)
    if line:
        doc += [line, ""]
    doc += ["### Ratio by material count and cost", "", ratio_table(series, ratio), ""]
    res = resource_table(rows)
    if res:
        priv = {v for r in rows for k, v in (r.get("kernel_resources") or {}).items()
                if k.endswith(".private_bytes")}
        same = (f" This device answers {next(iter(priv)):g} for every kernel, so here the "
                "column measures nothing." if len(priv) == 1 else "")
        doc += ["### Why, measured: per-work-item resources", "",
                "Registers and spill bytes from the NVIDIA build log (`-cl-nv-verbose`, NVIDIA "
                "only); private bytes from `CL_KERNEL_PRIVATE_MEM_SIZE`." + same, "", res, ""]
    st = stage_table(rows)
    if st:
        doc += ["### Why, measured: where the wavefront's time goes", "", st, ""]
    return doc
