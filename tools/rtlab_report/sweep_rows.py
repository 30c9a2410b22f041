"""What the charts (charts.py) and the generated READMEs (results_readme.py) read from sweep rows.

Nothing here knows which pipelines exist: a series is whatever `pipeline` values the rows hold,
split by `layout` where one pipeline ran several, and by `memory_budget`. A series is titled by
the rows' `pipeline_title` (else the short name); its colour and marker come from the one
palette in chart_style.py. How two series' times compare (ties, wins) is compare.py's.
Failures are read from the rows' `failure` field only.
Standard library only.
"""
FAILURES = {"private_tree": "private ray tree over rtlab's 256 KiB cap",
            "tree_row": "one row of the wavefront ray tree over the memory budget",
            "out_of_memory": "out of device memory",
            "opencl": "OpenCL error",
            "invalid_option": "invalid option",
            "skipped": "not run",
            "timeout": "did not finish within the cell time limit",
            "other": "error"}
FAILURES_SHORT = {"private_tree": "private tree > limit", "tree_row": "tree row > budget",
                  "out_of_memory": "out of memory", "opencl": "OpenCL error",
                  "invalid_option": "invalid option", "skipped": "not run",
                  "timeout": "timed out", "other": "error"}
# Rows written before the tree wavefront kept its traced flags apart do not record their tree's
# bytes per pixel; their tree had one 48-byte node (flags inside) per slot and nothing else.
# Newer rows carry tree_pixel_bytes.
LEGACY_NODE_BYTES = 48


def budget_label(b):
    if not b:
        return ""
    return f"{b / 2**30:g} GiB" if b >= 2**30 else f"{b / 2**20:g} MiB"


# Rows written before sweeps recorded each pipeline's design family and its own options: the
# pipelines and the one pipeline option (the megakernel's layout) that existed then.
LEGACY_FAMILIES = {"mega": "megakernel", "wave": "wavefront", "queue": "wavefront"}


def family(r):
    """The row's design family, as its pipeline's registry entry says: "megakernel",
    "wavefront"."""
    return r.get("family") or LEGACY_FAMILIES.get(r["pipeline"], r["pipeline"])


def own_options(r):
    """{name: value} of the options the row's own pipeline declares (its registry entry)."""
    if "options" in r:
        return r["options"]
    return {"layout": r.get("layout") or "tree"} if r["pipeline"] == "mega" else {}


def varying_options(rows):
    """{pipeline: [option names whose value differs among its rows]}, in declaration order."""
    seen = {}
    for r in rows:
        for name, value in own_options(r).items():
            seen.setdefault(r["pipeline"], {}).setdefault(name, set()).add(str(value))
    return {p: [n for n, v in opts.items() if len(v) > 1] for p, opts in seen.items()}


def option_part(name, value):
    """A series-key part: a choice by its name ("weighted"), a number with its option's
    ("pool=4096"), so that no part begins with a digit, as a budget's does."""
    return f"{name}={value}" if isinstance(value, (int, float)) else str(value)


class Series:
    """One line of a chart / one column of a table: a pipeline, the values of its own options
    where its rows hold several (the megakernel's layout), and a memory budget where one was
    set."""

    def __init__(self, rows):
        self.varying = varying_options(rows)
        self.titles = {}
        for r in rows:
            self.titles.setdefault(r["pipeline"], r.get("pipeline_title") or r["pipeline"])
        # A row of each series: its pipeline and own options pick the series' colour even where
        # an option takes one value in these rows and so is not part of the key.
        self.first = {}
        for r in rows:
            self.first.setdefault(self.key(r), r)
        self.keys = sorted(self.first)
        # Where a pipeline's rows vary in more than one option, a series is named by the options
        # its cells set away from their defaults, as the registry words them (the rows'
        # "option_labels": "nested loop", "256 lanes a group"), not by every value.
        self.described = {}
        for k, r in self.first.items():
            names = self.varying.get(r["pipeline"], ())
            if len(names) > 1 and "option_labels" in r:
                self.described[k] = [r["option_labels"][n] for n in names
                                     if n in r["option_labels"]] or ["defaults"]

    def key(self, r):
        k = r["pipeline"]
        own = own_options(r)
        for name in self.varying.get(r["pipeline"], ()):
            k += "/" + option_part(name, own.get(name))
        if r.get("memory_budget"):
            k += "/" + budget_label(r["memory_budget"]).replace(" ", "")
        return k

    def label(self, key):
        parts = key.split("/")
        text = self.titles.get(parts[0], parts[0])
        extra = self.described.get(key) or [p for p in parts[1:] if not p[0].isdigit()]
        budget = [p for p in parts[1:] if p[0].isdigit()]
        if extra:
            text += f" ({', '.join(extra)})"
        if budget:
            text += f", {budget[0].replace('MiB', ' MiB').replace('GiB', ' GiB')} budget"
        return text



def setting(r):
    """A cell's setting apart from the pipeline and its layout: what two series are compared at."""
    return (r["scene"], r["width"], r["height"], r["bounces"], r["shadow_samples"], r["aa"],
            r["accel"], r.get("adaptive"), r.get("memory_budget") or 0)


def by_setting(rows, series):
    """[(setting, {series key: row})] in sweep order, for settings at least two series ran."""
    by, order = {}, []
    for r in rows:
        k = setting(r)
        if k not in by:
            order.append(k)
        by.setdefault(k, {})[series.key(r)] = r
    return [(k, by[k]) for k in order if len(by[k]) > 1]


def fastest(cells):
    """The key of the fastest series in {key: row}."""
    return min(cells, key=lambda k: cells[k]["device_ms"])


def failure(r):
    """How a row ended: "" ran, else a kind of FAILURES (the rows' own field, nothing parsed)."""
    return r.get("failure") or ("" if r.get("status") == "ok" else "other")


def memory_tiles(r):
    return max(1, r.get("memory_tiles") or r.get("tiles") or 1)


def tree_sizes(r):
    """(bytes of one tile's tree, bytes of the whole frame's tree, tiles) of a row with a global
    ray tree, else None. The whole tree is width x height x the tree's bytes per pixel (payloads
    and flags, as the pipeline recorded them); the tile is what was allocated (tree_bytes)."""
    if not r.get("tree_bytes") or not r.get("tree_nodes"):
        return None
    pixel = r.get("extras", {}).get("tree_pixel_bytes") or r["tree_nodes"] * LEGACY_NODE_BYTES
    whole = r["width"] * r["height"] * pixel
    return r["tree_bytes"], whole, memory_tiles(r)


def in_group(rows, g):
    return [r for r in rows if g in r.get("groups", [])]


def limit_series(all_rows):
    """The limits group as series: one per scene, series key (pipeline, layout, budget) and
    axis. Along `bounces` the size is fixed, along `size` the bounce limit; a setting both axes
    share belongs to both. Each says the last setting that ran, where its global tree first
    tiled, and the first setting that failed (or was not run after an earlier failure)."""
    rows = in_group(all_rows, "limits")
    series = Series(rows)
    variants = {}
    for r in rows:
        variants.setdefault((r["scene"], series.key(r)), []).append(r)
    out = []
    for (scene, key), vrows in variants.items():
        axes = []
        by_size, by_b = {}, {}
        for r in vrows:
            by_size.setdefault((r["width"], r["height"]), []).append(r)
            by_b.setdefault(r["bounces"], []).append(r)
        size, srows = max(by_size.items(), key=lambda kv: len({r["bounces"] for r in kv[1]}))
        if len({r["bounces"] for r in srows}) > 1:
            axes.append(("bounces", f"at {size[0]}×{size[1]}",
                         sorted(srows, key=lambda r: r["bounces"])))
        b, brows = max(by_b.items(), key=lambda kv: len({(r["width"], r["height"]) for r in kv[1]}))
        if len({(r["width"], r["height"]) for r in brows}) > 1:
            axes.append(("size", f"at B={b}",
                         sorted(brows, key=lambda r: r["width"] * r["height"])))
        for axis, fixed, pts in axes:
            ran = [r for r in pts if failure(r) == ""]
            failed = [r for r in pts if failure(r) not in ("", "skipped")]
            skipped = [r for r in pts if failure(r) == "skipped"]
            tiled = [r for r in ran if memory_tiles(r) > 1]
            stop = failed[0] if failed else (skipped[0] if skipped else None)
            out.append({"scene": scene, "key": key, "label": series.label(key), "series": series,
                        "axis": axis, "fixed": fixed, "rows": pts, "ran": ran,
                        "last": ran[-1] if ran else None, "tiled": tiled[0] if tiled else None,
                        "stop": stop, "how": failure(stop) if stop else None,
                        "skipped": skipped})
    return out
