"""How `--pipeline auto` does against the designs it chooses from (bench/sweeps/auto): for each
scene, auto's device time against the better of the megakernel (either layout) and the queue
wavefront, the bar the designs-at-their-best question sets (within 5% of it everywhere, faster
than both somewhere), with the design auto chose, why, and the busy lanes it predicted. Each way
auto chooses (`--auto-choice predict`, the default, and `measure`, by trial frames) is scored on
its own, in a table of its own.

Beside that bar, auto is set against the best of every design that ran on the scene (both
megakernel layouts, the persistent megakernel, both wavefronts): the baseline a user who could
pick any design by hand would have. Auto's time is its chosen design's frame: the decision
(the CPU prediction, or the trial frames, and the programs built for them) is not in it.

A gap inside the measured frame spread is no gap (compare.py's tie rule): auto "within 5%" means
its time is at most 1.05 times the better one's or ties it, and "faster than both" means faster
than each beyond the spread.

Usage: python3 -m rtlab_report auto-eval ROWS.jsonl [ROWS.jsonl...] [--out FILE.md]
Rows of one scene from several files are pooled (a later file's cell replaces an earlier one's),
so that auto measured again at a later commit can be set against the designs measured before;
the table names each row's commit. Standard library only.
"""
import argparse
import json
import sys

from .compare import tied
from .sweep_rows import own_options

BAR = 1.05


# How auto chose (its auto-choice option) -> the series name its rows get; predict is the default.
AUTO_SERIES = {"predict": "auto", "measure": "auto-measure"}
AUTO_TITLES = {"auto": "by prediction (`--auto-choice predict`, the default)",
               "auto-measure": "by trial frames (`--auto-choice measure`)"}


def design(r):
    """mega-tree, mega-weighted, wave, queue, persist, auto, auto-measure: the series a row
    belongs to."""
    if r["pipeline"] == "mega":
        return "mega-" + own_options(r).get("layout", "tree")
    if r["pipeline"] == "auto":
        choice = own_options(r).get("auto-choice", "predict")
        return AUTO_SERIES.get(choice, "auto-" + choice)
    return r["pipeline"]


def load(paths):
    cells = {}
    for path in paths:
        with open(path) as f:
            for line in f:
                if not line.strip():
                    continue
                r = json.loads(line)
                if r.get("status") == "ok":
                    cells.setdefault(r["scene"], {})[design(r)] = r
    return cells


def evaluate(cells, auto="auto"):
    """[(scene, row dict, auto, best, ratio, within, faster)] for scenes where the auto series
    `auto`, the queue and a megakernel ran."""
    out = []
    for scene, d in cells.items():
        megas = [d[k] for k in ("mega-weighted", "mega-tree") if k in d]
        if auto not in d or "queue" not in d or not megas:
            continue
        mega = min(megas, key=lambda r: r["device_ms"])
        best = min((mega, d["queue"]), key=lambda r: r["device_ms"])
        a = d[auto]
        ratio = a["device_ms"] / best["device_ms"]
        within = ratio <= BAR or tied(a, best)
        faster = all(a["device_ms"] < r["device_ms"] and not tied(a, r) for r in (mega, d["queue"]))
        out.append((scene, d, a, best, ratio, within, faster))
    return out


DESIGNS = ("mega-weighted", "mega-tree", "persist", "wave", "queue")


def against_every_design(d, a):
    """(the fastest design of every one that ran, auto's ratio to it, within 5% or tied)."""
    ran = [d[k] for k in DESIGNS if k in d]
    if not ran:
        return None, float("nan"), False
    best = min(ran, key=lambda r: r["device_ms"])
    ratio = a["device_ms"] / best["device_ms"]
    return best, ratio, ratio <= BAR or tied(a, best)


def table(results, auto="auto", heading="#"):
    cols = ["mega-weighted", "mega-tree", "wave", "queue", "persist"]
    first = results[0][2] if results else {}
    commits = sorted({r.get("commit", "?")[:12] for _, d, *_ in results for r in d.values()})
    lines = [f"{heading} `--pipeline auto` {AUTO_TITLES.get(auto, auto)} against the designs it "
             "chooses from",
             "",
             f"{first.get('device', '?')}, driver {first.get('driver', '?')}, "
             f"commit{'s' if len(commits) > 1 else ''} {', '.join(f'`{c}`' for c in commits)}; "
             f"{first.get('width')}x{first.get('height')}, B = {first.get('bounces')}, accel "
             f"{first.get('accel')}; device ms, median of {first.get('repeats')} frames after "
             f"{first.get('warmup')} warm-up frames. Ratio: auto over the better of the megakernel "
             f"(either layout) and the queue; *tie* where the gap is inside the frame spread.",
             "",
             "| scene | auto | " + " | ".join(cols) + " | ratio | vs the best of every design "
             "| auto chose | busy lanes predicted |",
             "|" + "---|" * (len(cols) + 6)]
    every = []
    for scene, d, a, best, ratio, within, faster in sorted(results):
        x = a.get("extras") or {}
        cells = [f"{d[c]['device_ms']:.3f}" if c in d else "—" for c in cols]
        verdict = f"{ratio:.3f}" + ("" if within else " **over 5%**") + \
            (" **faster than both**" if faster else "") + \
            (" (tie)" if tied(a, best) and not faster else "")
        lanes = x.get("auto_busy_lanes")
        best_all, ratio_all, within_all = against_every_design(d, a)
        every.append((scene, ratio_all, within_all))
        versus = f"{ratio_all:.3f}" + ("" if within_all else " **over 5%**") + \
            (f" ({best_all['pipeline']})" if best_all is not None else "")
        lines.append(f"| `{scene}` | {a['device_ms']:.3f} | " + " | ".join(cells) +
                     f" | {verdict} | {versus} | {x.get('auto_design', '?')} | "
                     f"{'—' if lanes is None else f'{lanes:.1f}'} |")
    n = len(results)
    over = [s for s, *_, w, f in results if not w]
    faster = [s for s, *_, f in results if f]
    worst = max(results, key=lambda t: t[4]) if results else None
    lines += ["",
              f"Within 5% of the better of mega and queue (or tied with it) on {n - len(over)} of "
              f"{n} scenes; faster than both beyond the spread on {len(faster)}."
              + (f" Over 5%: {', '.join(f'`{s}`' for s in over)}." if over else "")
              + (f" Worst ratio {worst[4]:.3f} (`{worst[0]}`)." if worst else ""),
              "",
              f"Against the best of every design that ran (the persistent megakernel and the "
              f"tree wavefront included): within 5% or tied on "
              f"{sum(1 for _, _, w in every if w)} of {len(every)} scenes"
              + (f", worst ratio {max(r for _, r, _ in every):.3f}" if every else "") + ". "
              "Auto's times leave out its decision (the CPU prediction, or trial frames, and "
              "the programs built for them)."]
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rows", nargs="+", help="sweep rows (rows.jsonl) of bench/sweeps/auto")
    ap.add_argument("--out", help="write the Markdown table here (default: stdout)")
    args = ap.parse_args(argv)
    cells = load(args.rows)
    present = [a for a in AUTO_SERIES.values() if any(a in d for d in cells.values())]
    present += sorted({k for d in cells.values() for k in d
                       if k.startswith("auto") and k not in present})
    several = len(present) > 1
    text = "\n".join(table(evaluate(cells, a), a, "##" if several else "#") for a in present)
    if several:
        text = "# `--pipeline auto` against the designs it chooses from\n\n" + text
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)

