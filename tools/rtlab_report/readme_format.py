"""Number and table formatting of the generated READMEs (results_readme.py, readme_limits.py).
Standard library only.
"""
import math
import os

from .sweep_rows import tree_sizes


def clean_meta(meta, rows=None):
    """The sweep's metadata as the README shows it: counts as integers (an import that joins a
    continued run sums them as floats), the sweep file by its place in the repository (rtlab-bench
    on a GPU machine ran a copy), and how many device runs were joined instead of local paths."""
    m = dict(meta)
    if rows is not None:
        # Count from the rows: a continued run re-measures the cells that failed before, so the
        # sums of the runs' own counts would count those cells twice.
        count = lambda status: sum(1 for r in rows if r.get("status") == status)
        m.update(measured=count("ok"), failed=count("error"), not_run=count("skipped"))
    for k in ("measured", "failed", "not_run", "cells"):
        if isinstance(m.get(k), float) and m[k].is_integer():
            m[k] = int(m[k])
    if m.get("config_file") and os.path.isabs(m["config_file"]):
        m["config_file"] = "bench/sweeps/" + os.path.basename(m["config_file"])
    if m.get("imported_from"):
        n = len(m["imported_from"].split(" + "))
        if m.get("shards"):  # --shard i/N runs, merged in cell order (and continued, if n > N)
            m["imported_from"] = f"{n} device runs: shards {', '.join(m['shards'])}"
        else:
            m["imported_from"] = (f"{n} device runs, each continuing the one before"
                                  if n > 1 else "one device run")
    return m


def geomean(xs):
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def ms(x):
    if x is None:
        return "—"
    return f"{x:.3g}" if x < 100 else f"{x:.0f}"


def table(head, body):
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in body]
    return "\n".join(lines)


def accel_label(r):
    return "—" if r["accel"] == "-" else r["accel"]


def size_label(r):
    return f"{r['width']}×{r['height']}"


def gib(b):
    if not b:
        return "?"
    return f"{b / 2**30:.3g} GiB" if b >= 2**30 else f"{b / 2**20:.3g} MiB"


def tree_text(cells):
    """The global ray tree of a setting: one tile's allocation and the whole frame's tree."""
    out = []
    for r in cells.values():
        sizes = tree_sizes(r)
        if sizes:
            tile, whole, tiles = sizes
            out.append(f"{gib(whole)} whole" if tiles <= 1 else
                       f"{tiles} tiles of {gib(tile)}; {gib(whole)} whole")
    return "; ".join(out) or "—"
