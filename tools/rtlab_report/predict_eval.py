"""How often `rtlab predict` names the winner: reads the predictions (`rtlab predict --json`, one
object a scene) and measured sweep rows, finds the fastest design of every scene where every
design ran (a tie by compare.py's rule, through charts_map.verdict), fits the
busy-lane threshold on the FIT rows, and scores the rule on them and on the TEST rows, which it
was not fitted to. The question scored is the one the rule answers: does the queue wavefront win,
or a design that gives each work-item a whole ray tree (the megakernel in either layout, or the
report's tree wavefront)? Settings where the queue and a design of the other kind tie are left out of the score and
counted apart; a tie between two designs of one kind still answers the question.

Usage: python3 -m rtlab_report predict --predictions P.jsonl --fit ROWS.jsonl... --test ROWS.jsonl...
                               [--threshold T] [--out FILE.md] [--chart FILE.png]
The rule is scored at the threshold rtlab ships (auto/thresholds.h, or
--threshold): that is the rule `auto` and `rtlab predict` apply. The threshold that would fit
these FIT rows best is found too and stated beside it, never silently put in its place; the
FIT rows are called the fit set, the TEST rows the test set.
The table needs the standard library only; the chart (the queue's time over the best of the
other kind against the predicted busy lanes, with the fitted threshold) needs matplotlib.
"""
import argparse
import json
import os
import re
import sys

from .charts_map import load, verdict
from .sweep_rows import Series, family, own_options


SHIPPED_SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "auto",
                              "thresholds.h")


def shipped_threshold(path=SHIPPED_SOURCE):
    """The GPU rule's queue threshold as auto/thresholds.h defines it (kGpuThresholds), or None
    without the source."""
    try:
        with open(path) as f:
            m = re.search(r"kGpuThresholds\{\s*([0-9.]+)", f.read())
    except OSError:
        return None
    return float(m.group(1)) if m else None


def scene_key(path_or_name):
    """A scene's name as the sweep rows give it: its path under the scene folder, no extension."""
    p = path_or_name.replace("\\", "/")
    if "scenes/" in p:
        p = p.split("scenes/", 1)[1]
    return p[:-5] if p.endswith(".json") else p


def settings(files):
    """[(scene, winner key, runner-up, margin, tie, series, rows)] where every design ran."""
    out, meta = [], {}
    for path in files:
        m, rows = load(path)
        meta = meta or m
        # A selector (`--pipeline auto`) renders with one of the designs scored here: its win
        # would be that design's, and the question is which kind of design wins.
        rows = [r for r in rows if family(r) != "selector"]
        series = Series(rows)
        by_scene = {}
        for r in rows:
            by_scene.setdefault((r["scene"], r["width"], r["height"], r["bounces"]), {})[series.key(r)] = r
        for (scene, *_), by_key in sorted(by_scene.items()):
            v = verdict(by_key, series.keys)
            if v:
                out.append((scene, v[0], v[1], v[2], v[3], series, by_key))
                continue
            # Some design did not run: the question is still settled where a design that ran
            # beats the queue, since the best of all can only be faster still.
            ran = [k for k, r in by_key.items() if r.get("status") == "ok"]
            if "queue" in ran and len(ran) >= 2:
                v = verdict({k: by_key[k] for k in ran}, ran)
                # A tie between two designs of the other kind still settles it.
                if v and not is_queue(v[0]) and not undecided(v[0], v[1], v[3]):
                    out.append((scene, v[0], v[1], v[2], v[3], series, by_key, "partial"))
    return meta, out


def is_queue(key):
    return key.split("/")[0] == "queue"


def undecided(winner, runner, tie):
    """A tie leaves the question open only between the queue and a design of the other kind."""
    return tie and is_queue(winner) != is_queue(runner)


def fit_threshold(points):
    """The threshold between two neighbouring lane counts that scores best; the midpoint."""
    lanes = sorted({p[0] for p in points})
    candidates = [0.0] + [(a + b) / 2 for a, b in zip(lanes, lanes[1:])] + [32.0]
    def hits(t):
        return sum((l < t) == queue for l, queue in points)
    best = max(hits(t) for t in candidates)
    good = [t for t in candidates if hits(t) == best]
    return (good[0] + good[-1]) / 2 if good else 25.0


def score(rows, predictions, threshold):
    lines, hits, scored, ties, missing, worst = [], 0, 0, 0, 0, 1.0
    for scene, winner, runner, margin, tie, series, by_key, *partial in rows:
        tie = undecided(winner, runner, tie)
        p = predictions.get(scene_key(scene))
        if p is None:
            missing += 1
            continue
        truth = winner.split("/")[0] == "queue"
        predicted = p["busy_lanes"] < threshold
        measured = [r.get("extras", {}).get("warp_lanes_active") for r in by_key.values()
                    if family(r) == "megakernel" and own_options(r).get("layout") == "weighted"]
        measured = next((m for m in measured if m is not None), None)
        ok = "tie" if tie else ("yes" if truth == predicted else "**no**")
        if not tie and truth != predicted:
            # What the wrong pick costs: the fastest design of the predicted kind over the winner.
            ran = {k: r["device_ms"] for k, r in by_key.items() if r.get("status") == "ok"}
            picked = [t for k, t in ran.items() if (k.split("/")[0] == "queue") == predicted]
            if picked:
                ok += f" ({min(picked) / ran[winner]:.2f}x slower)"
                worst = max(worst, min(picked) / ran[winner])
        if tie:
            ties += 1
        else:
            scored += 1
            hits += truth == predicted
        lines.append(f"| {scene_key(scene)} | {p['busy_lanes']:.1f} | "
                     f"{'-' if measured is None else f'{measured:.1f}'} | "
                     f"{'queue' if predicted else 'tree a work-item'} | {series.label(winner)}"
                     f"{' (of those that ran: ' + ', '.join(sorted(by_key)) + ')' if partial else ''} | "
                     f"{margin:.2f}x | {ok} |")
    return lines, hits, scored, ties, missing, worst


def chart(meta, groups, predictions, threshold, path, fitted=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .chart_style import figure, legend_row, log_ticks

    fig, (ax,), legend_ax = figure(meta, "The queue wavefront's frame time over the best design "
                                   "with one ray tree a work-item, against the busy lanes "
                                   "`rtlab predict` counts on the CPU", 1, cols=1, panel=(8, 4.2))
    handles = []
    # Fit and test sets are not designs: greys, told apart by marker (no design colour reused).
    for (title, rows), (color, marker) in zip(groups, (("#888888", "o"), ("#111111", "^"))):
        xs, ys = [], []
        for scene, winner, runner, margin, tie, series, by_key, *partial in rows:
            p = predictions.get(scene_key(scene))
            ran = {k: r["device_ms"] for k, r in by_key.items() if r.get("status") == "ok"}
            others = [t for k, t in ran.items() if not is_queue(k)]
            if p is None or "queue" not in ran or not others:
                continue
            xs.append(p["busy_lanes"])
            ys.append(ran["queue"] / min(others))
        if xs:
            # Hollow markers: where points of the two sets fall together, both stay visible.
            handles.append(ax.scatter(xs, ys, s=30, facecolors="none", edgecolors=color,
                                      marker=marker, linewidths=1.2,
                                      label=f"{title} ({len(xs)})"))
    ax.axhline(1.0, color="#555555", linewidth=0.8)
    ax.set_yscale("log")
    log_ticks(ax)
    # Headroom above the points for the thresholds' labels (log axis: a factor).
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi * 1.45)
    top = hi * 1.4
    ax.axvline(threshold, color="#222222", linewidth=1.0, linestyle="--")
    ax.text(threshold, top, f"shipped threshold {threshold:.1f} ", va="top", ha="right",
            fontsize=8)
    if fitted is not None and abs(fitted - threshold) >= 0.05:
        # The best fit to these rows, where it differs from the rule rtlab applies.
        ax.axvline(fitted, color="#888888", linewidth=0.8, linestyle=":")
        ax.text(fitted, top / 1.15, f"best fit to the fit set {fitted:.2f} ", va="top",
                ha="right", fontsize=8, color="#555555")
    ax.set_xlim(0, 32.5)
    ax.set_xlabel("predicted busy lanes of 32 (weighted megakernel)")
    ax.set_ylabel("queue time / best other (below 1: queue wins)")
    legend_row(legend_ax, handles, [h.get_label() for h in handles], ncol=len(handles))
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--predictions", required=True)
    ap.add_argument("--fit", nargs="+", required=True)
    ap.add_argument("--test", nargs="*", default=[])
    ap.add_argument("--threshold", type=float,
                    help="busy lanes below which the queue is named [auto/thresholds.h]")
    ap.add_argument("--out")
    ap.add_argument("--chart")
    a = ap.parse_args(argv)
    predictions = {}
    with open(a.predictions) as f:
        for line in f:
            if line.strip():
                p = json.loads(line)
                predictions[scene_key(p["scene"])] = p
    meta, fit = settings(a.fit)
    _, test = settings(a.test) if a.test else ({}, [])
    points = [(predictions[scene_key(s)]["busy_lanes"], w.split("/")[0] == "queue")
              for s, w, u, _, tie, _, _, *rest in fit
              if not undecided(w, u, tie) and scene_key(s) in predictions]
    if not points:
        sys.exit("predict_eval: no setting of the fit set has a prediction (scene names differ?)")
    fitted = fit_threshold(points)
    t = a.threshold if a.threshold is not None else shipped_threshold()
    if t is None:
        sys.exit("predict_eval: no auto/thresholds.h to read the shipped threshold from; "
                 "give --threshold")
    _, fit_hits, fit_scored, *_ = score(fit, predictions, fitted)
    head = ["| scene | predicted busy lanes | measured (weighted) | predicted | fastest | margin | right |",
            "|---|---|---|---|---|---|---|"]
    out = [f"# The predictor on {meta.get('device', '?')} (driver {meta.get('driver', '?')}, "
           f"commit {meta.get('commit', '?')})", "",
           f"Rule, as rtlab ships it: the queue wavefront wins below **{t:.1f}** busy lanes of "
           "32, a design with one ray tree a work-item at or above. Busy lanes predicted by "
           "`rtlab predict` (CPU, 2048 warps of 16x2 pixels, no shading); measured ones from the "
           "weighted megakernel's counting frame. The threshold that fits this fit set best "
           f"(the {len(points)} settings not tied between the two kinds) is {fitted:.2f}, which "
           f"scores {fit_hits} of {fit_scored} on it; the scores below are the shipped rule's.",
           ""]
    for title, rows in (("Fit set", fit), ("Test set (not fitted to)", test)):
        if not rows:
            continue
        lines, hits, scored, ties, missing, worst = score(rows, predictions, t)
        out += [f"## {title}: {hits} of {scored} right" + (f" ({100 * hits / scored:.0f}%)" if scored else "") +
                f", {ties} ties between the kinds left out" + (f", {missing} without a prediction" if missing else "") +
                (f"; a wrong pick costs at most {worst:.2f}x" if hits < scored else ""),
                ""] + head + lines + [""]
    text = "\n".join(out) + "\n"
    if a.chart:
        chart(meta, [("fit set", fit), ("test set", test)], predictions, t, a.chart, fitted)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    print(text)
