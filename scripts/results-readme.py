#!/usr/bin/python3
"""Writes results/<device-slug>/README.md from the JSON of a sweep (`rtlab sweep` runs this).

Usage: /usr/bin/python3 scripts/results-readme.py results/<device-slug>/<sweep>.json [--out FILE]

The README holds the tables the report's results chapter left empty (per scene: number of
objects, spheres, triangles, acceleration structures, resolution, and the two pipelines' times),
which pipeline wins on each scene and by what ratio, the time-against-bounce-limit and
acceleration tables, the Pareto front of speed against accuracy, failed cells, and the charts.
A folder may hold several sweeps of one device: the README covers them all, the `limits` sweep
(bench/sweeps/limits) in its own section (per pipeline the last setting that ran, its time and
memory, and how the first failing one failed).
Every figure comes from the JSON; the header says which device, driver, commit and settings.

When the set lives in a folder named results/, results/README.md, the index of every result set
there (device, commit, which pipeline wins on each scene, the speed-against-accuracy chart), is
rewritten too; `--index results` rewrites only that.
Standard library only.
"""
import argparse
import json
import math
import os
import sys

NAMES = {"mega": "megakernel", "wave": "wavefront"}
CHARTS = [("time-vs-resolution.png", "Frame time against resolution"),
          ("time-vs-bounces.png", "Frame time against bounce limit"),
          ("memory-vs-bounces.png", "Device memory against bounce limit"),
          ("kernel-breakdown.png", "Device time per kernel"),
          ("speed-vs-accuracy.png", "Speed against accuracy, Pareto front marked")]


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
        m["imported_from"] = (f"{n} device runs, each continuing the one before"
                              if n > 1 else "one device run")
    return m


def setting(r):
    return (r["scene"], r["width"], r["height"], r["bounces"], r["shadow_samples"], r["aa"],
            r["accel"], r.get("layout"), r.get("adaptive"))


def pairs(rows):
    """(mega row, wave row) for every setting measured on both pipelines, in sweep order."""
    by = {}
    order = []
    for r in rows:
        k = setting(r)
        if k not in by:
            order.append(k)
        by.setdefault(k, {})[r["pipeline"]] = r
    return [(by[k]["mega"], by[k]["wave"]) for k in order if "mega" in by[k] and "wave" in by[k]]


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


def in_group(rows, g):
    return [r for r in rows if g in r.get("groups", [])]


def accel_label(r):
    return "—" if r["accel"] == "-" else r["accel"]


def verdict(ratio):
    """wave/mega time ratio -> 'megakernel, 1.8x faster'."""
    if ratio > 1:
        return f"megakernel, {ratio:.2f}× faster"
    return f"wavefront, {1 / ratio:.2f}× faster"


def scene_table(rows):
    """Report table: per scene and resolution, object counts and both pipelines' times."""
    chosen = in_group(rows, "resolution") or rows
    body = []
    for mega, wave in pairs(chosen):
        info = mega["scene_info"]
        ratio = wave["device_ms"] / mega["device_ms"]
        body.append([mega["scene"], info["objects"], info["spheres"], info["triangles"],
                     accel_label(mega), f"{mega['width']}×{mega['height']}",
                     f"B={mega['bounces']} s={mega['shadow_samples']} aa={mega['aa']}",
                     ms(mega["device_ms"]), ms(wave["device_ms"]), f"{ratio:.2f}"])
    return table(["Scene", "No. objects", "Spheres", "Triangles", "Acceleration structures",
                  "Resolution", "Settings", "Megakernel ms", "Wavefront ms", "wave/mega"], body)


def winner_table(rows):
    by_scene = {}
    for mega, wave in pairs(rows):
        by_scene.setdefault(mega["scene"], []).append(wave["device_ms"] / mega["device_ms"])
    body = []
    for scene, ratios in by_scene.items():
        g = geomean(ratios)
        wins = sum(1 for x in ratios if x > 1)
        body.append([scene, len(ratios), f"{g:.2f}", f"{min(ratios):.2f} – {max(ratios):.2f}",
                     f"{wins} / {len(ratios)}", verdict(g)])
    return table(["Scene", "Paired cells", "wave/mega (geometric mean)", "range",
                  "cells the megakernel wins", "Winner"], body), by_scene


def bounce_table(rows):
    body = []
    for mega, wave in pairs(in_group(rows, "bounces")):
        used = wave.get("tree_used")
        body.append([mega["scene"], f"{mega['width']}×{mega['height']}", mega["bounces"],
                     mega["tree_nodes"], ms(mega["device_ms"]), ms(wave["device_ms"]),
                     f"{wave['device_ms'] / mega['device_ms']:.2f}",
                     f"{wave['device_bytes'] / 2**20:.1f}", wave.get("tiles", 1),
                     "—" if used is None else f"{100 * used:.1f}%"])
    return table(["Scene", "Resolution", "B", "Tree nodes N", "Megakernel ms", "Wavefront ms",
                  "wave/mega", "Wavefront MiB", "Tiles", "Tree slots used"], body)


def accel_table(rows):
    """Each structure against brute force on the same view, per pixel (sizes may differ)."""
    chosen = [r for r in in_group(rows, "accel") if r["accel"] != "-"]
    base = {(r["scene"], r["pipeline"], r["bounces"]): r for r in chosen if r["accel"] == "none"}
    body = []
    for r in chosen:
        b = base.get((r["scene"], r["pipeline"], r["bounces"]))
        ratio = "—"
        if b:
            per_px = (r["device_ms"] / (r["width"] * r["height"])) / (
                b["device_ms"] / (b["width"] * b["height"]))
            ratio = f"{per_px:.4g}"
        body.append([r["scene"], NAMES[r["pipeline"]], f"{r['width']}×{r['height']}", r["bounces"],
                     r["accel"], ms(r["device_ms"]), ratio])
    return table(["Scene", "Pipeline", "Resolution", "B", "Accel", "Device ms",
                  "accel/none (time per pixel)"], body)


def pareto_table(rows):
    scored = [r for r in in_group(rows, "accuracy") if "rmse" in r]
    body = []
    for scene in dict.fromkeys(r["scene"] for r in scored):
        best = float("inf")
        for r in sorted((r for r in scored if r["scene"] == scene),
                        key=lambda r: (r["device_ms"], r["rmse"])):
            if r["rmse"] < best:
                best = r["rmse"]
                body.append([scene, NAMES[r["pipeline"]], r["bounces"], r["shadow_samples"],
                             r["aa"], ms(r["device_ms"]), f"{r['rmse']:.4f}",
                             f"{r['psnr_db']:.1f}"])
    return table(["Scene", "Pipeline", "B", "Shadow samples", "AA", "Device ms", "RMSE",
                  "PSNR dB"], body)


# ---- limits (bench/sweeps/limits): how far each pipeline goes ----

FAILURE_TEXT = {"private tree": "private ray tree over the per-work-item limit",
                "tree row": "one row of the wavefront tree over the memory budget",
                "allocation": "device allocation failed",
                "OpenCL error": "OpenCL error",
                "other": "error"}


def gib(b):
    if not b:
        return "?"
    return f"{b / 2**30:.3g} GiB" if b >= 2**30 else f"{b / 2**20:.3g} MiB"


def budget_label(b):
    if not b:
        return ""
    return f"{b / 2**30:g} GiB" if b >= 2**30 else f"{b / 2**20:g} MiB"


def size_label(r):
    return f"{r['width']}×{r['height']}"


def failure_kind(r):
    """A failed row's kind: recorded since the limits sweep, else guessed from the message."""
    if r.get("failure"):
        return r["failure"]
    e = r.get("error", "")
    if "in private memory" in e:
        return "private tree"
    if "one row of the wavefront ray tree" in e:
        return "tree row"
    if "ALLOCATION" in e or "OUT_OF_RESOURCES" in e or "per allocation" in e:
        return "allocation"
    return "OpenCL error" if "CL_" in e else "other"


def memory_tiles(r):
    if "memory_tiles" in r:
        return r["memory_tiles"]
    if r.get("pipeline") != "wave" or not r.get("tree_bytes") or not r.get("tree_nodes"):
        return 1
    rows = round(r["tree_bytes"] / (r["width"] * r["tree_nodes"] * 48))
    return max(1, -(-r["height"] // max(rows, 1)))


def limit_series(all_rows):
    """The limits group as series: one per scene, pipeline variant (layout, memory budget) and
    axis. Along `bounces` the size is fixed, along `size` the bounce limit; a setting both axes
    share belongs to both. Each series says the last setting that ran, where the wavefront tree
    first tiled, and the first setting that failed (or was not run after a too-long frame)."""
    rows = in_group(all_rows, "limits")
    variants = {}
    for r in rows:
        layout = r.get("layout", "tree") if r["pipeline"] == "mega" else "tree"
        key = (r["scene"], r["pipeline"], layout, r.get("memory_budget") or 0)
        variants.setdefault(key, []).append(r)
    out = []
    for (scene, pipe, layout, budget), vrows in variants.items():
        label = NAMES.get(pipe, pipe)
        if pipe == "mega":
            label += f" ({layout})"
        if budget:
            label += f", {budget_label(budget)} budget"
        axes = []
        by_size = {}
        for r in vrows:
            by_size.setdefault((r["width"], r["height"]), []).append(r)
        size, srows = max(by_size.items(), key=lambda kv: len({r["bounces"] for r in kv[1]}))
        if len({r["bounces"] for r in srows}) > 1:
            axes.append(("bounces", f"at {size[0]}×{size[1]}", sorted(srows, key=lambda r: r["bounces"])))
        by_b = {}
        for r in vrows:
            by_b.setdefault(r["bounces"], []).append(r)
        b, brows = max(by_b.items(), key=lambda kv: len({(r["width"], r["height"]) for r in kv[1]}))
        if len({(r["width"], r["height"]) for r in brows}) > 1:
            axes.append(("size", f"at B={b}", sorted(brows, key=lambda r: r["width"] * r["height"])))
        for axis, fixed, pts in axes:
            ran = [r for r in pts if r.get("status") == "ok"]
            failed = [r for r in pts if r.get("status") not in ("ok", "skipped")]
            skipped = [r for r in pts if r.get("status") == "skipped"]
            tiled = [r for r in ran if memory_tiles(r) > 1]
            stop, how = None, None
            if failed:
                stop, how = failed[0], failure_kind(failed[0])
            elif skipped:
                stop = skipped[0]
                how = "time cap" if "max-frame-s" in stop.get("skip_reason", "") else "skipped"
            out.append({"scene": scene, "pipeline": pipe, "layout": layout, "budget": budget,
                        "label": label, "axis": axis, "fixed": fixed, "rows": pts, "ran": ran,
                        "last": ran[-1] if ran else None, "tiled": tiled[0] if tiled else None,
                        "stop": stop, "how": how, "skipped": skipped})
    return out


def setting_of(r, axis):
    return f"B={r['bounces']}" if axis == "bounces" else size_label(r)


def how_text(series):
    how = series["how"]
    if how is None:
        return "— (every setting ran)"
    if how == "time cap":
        reason = series["stop"].get("skip_reason", "")
        return f"not run: {reason.split('(', 1)[-1].split(')')[0]}" if "(" in reason else "not run (time cap)"
    stop = series["stop"]
    if stop.get("status") == "skipped":
        return "not run"
    return f"error: {FAILURE_TEXT.get(how, how)}"


def limits_table(all_rows):
    body = []
    for s in limit_series(all_rows):
        last, tiled, stop, axis = s["last"], s["tiled"], s["stop"], s["axis"]
        lr = "—"
        if last:
            launches = f"{last.get('launches', '?')}"
            if last.get("longest_launch_ms") is not None:
                launches += f" (longest {ms(last['longest_launch_ms'])} ms)"
            lr = (f"{setting_of(last, axis)}: {ms(last['device_ms'])} ms, "
                  f"{gib(last.get('device_bytes'))}, {launches} launches")
        tiles = "—"
        if tiled:
            tiles = f"{setting_of(tiled, axis)} ({memory_tiles(tiled)} tiles)"
        body.append([s["scene"], s["label"], f"{'bounce limit' if axis == 'bounces' else 'resolution'} "
                     f"{s['fixed']}", lr, tiles, setting_of(stop, axis) if stop else "—", how_text(s)])
    return table(["Scene", "Pipeline", "Axis (fixed)", "Last that ran: device ms, global memory, "
                  "launches", "Wavefront tree tiles from", "First failure", "How it failed"], body)


def limits_summary(all_rows):
    """The index's short form: per pipeline and axis, the last setting that ran and the first
    that failed."""
    body = []
    for s in limit_series(all_rows):
        last, stop, axis = s["last"], s["stop"], s["axis"]
        body.append([s["scene"], s["label"],
                     f"{'bounce limit' if axis == 'bounces' else 'resolution'} {s['fixed']}",
                     f"{setting_of(last, axis)} ({ms(last['device_ms'])} ms)" if last else "—",
                     f"{setting_of(stop, axis)}: {how_text(s)}" if stop else how_text(s)])
    return table(["Scene", "Pipeline", "Axis", "Last that ran", "First failure"], body)


def limits_section(data, json_rel, chart_exists):
    meta, all_rows = clean_meta(data["meta"], data["rows"]), data["rows"]
    rows = in_group(all_rows, "limits")
    if not rows:
        return []
    first = rows[0]
    cap = first.get("max_frame_s")
    launch = first.get("max_launch_ms")
    errors = {}
    for r in rows:
        if r.get("status") == "error":
            errors.setdefault(r.get("error", ""), []).append(r)
    compared = [r for r in rows if "image_max_diff" in r and r["pipeline"] == "mega"]
    differing = [r for r in compared if r["image_max_diff"] != 0]
    nonfinite = [r for r in rows if r.get("image_nonfinite")]
    doc = ["## Limits: how far each pipeline goes",
           "",
           f"From [`{json_rel}`]({json_rel}) (sweep `{meta.get('config_file')}`, commit "
           f"`{meta.get('commit')}`, measured {meta.get('started')} to {meta.get('finished')}; "
           f"{meta.get('measured')} cells ran, {meta.get('failed')} failed, "
           f"{meta.get('not_run', 0)} not run). Per pipeline the bounce limit goes up at a fixed "
           "size and the resolution at a fixed bounce limit. Once a setting fails"
           + (f" (or one of its frames takes longer than {cap:g} s)" if cap else "")
           + ", the settings of that pipeline that are no smaller are not run. "
           + (f"Frames are split so that no launch should run past {launch:g} ms (display "
              "watchdogs); the launches per frame and the longest one are recorded. " if launch else "")
           + f"Device max allocation {gib(meta.get('max_alloc_bytes'))}, global memory "
           f"{gib(meta.get('global_mem_bytes'))}.",
           "",
           limits_table(all_rows),
           ""]
    if errors:
        doc += ["How each failing setting failed (the message the user gets):", ""]
        for msg, rs in errors.items():
            where = ", ".join(f"{r['pipeline']} {size_label(r)} B={r['bounces']}" for r in rs[:4])
            doc.append(f"- {where}{' …' if len(rs) > 4 else ''}: `{msg}`")
        doc.append("")
    if compared:
        doc.append(f"Frames of both pipelines were compared at the {len(compared)} settings both ran: "
                   + ("bit-identical at every one." if not differing else
                      f"{len(differing)} differ (largest |difference| "
                      f"{max(r['image_max_diff'] for r in differing):g}).")
                   + (" No frame has a NaN or infinite pixel." if not nonfinite else
                      f" {len(nonfinite)} frames have NaN or infinite pixels."))
        doc.append("")
    timed = [r for r in rows if r.get("status") == "ok" and r.get("longest_launch_ms") is not None]
    if launch and timed:
        over = [r for r in timed if r["longest_launch_ms"] > launch]
        worst = max(timed, key=lambda r: r["longest_launch_ms"])
        if not over:
            doc.append(f"Every launch of the {len(timed)} cells that ran stayed under "
                       f"max-launch-ms = {launch:g} (longest {ms(worst['longest_launch_ms'])} ms).")
        else:
            longest = sorted(r["longest_launch_ms"] for r in over)
            doc.append(f"**Launches over max-launch-ms = {launch:g}:** {len(over)} of the {len(timed)} "
                       f"cells that ran had a longer one (median of their longest launches "
                       f"{ms(longest[len(longest) // 2])} ms; the worst "
                       f"{ms(worst['longest_launch_ms'])} ms, {worst['pipeline']} "
                       f"{size_label(worst)} B={worst['bounces']}"
                       f"{' weighted' if worst.get('layout') == 'weighted' else ''}). Tiles are "
                       "planned from each row's cost measured in the earlier frames of the same "
                       "setting, aiming at 80% of the target; a launch runs over when its rows "
                       "cost more than they did a frame before (other load on the machine: host "
                       f"load average {meta.get('host_load_start', '?')} at the start, "
                       f"{meta.get('host_load_end', '?')} at the end) or when a single row costs "
                       "more than the target.")
        doc.append("")
    if chart_exists:
        doc += ["![Limits: time, memory and longest launch against bounce limit and resolution]"
                "(limits.png)", ""]
    body = []
    for r in rows:
        body.append([r["pipeline"] + (" weighted" if r.get("layout") == "weighted" and
                                      r["pipeline"] == "mega" else "")
                     + (f" ({budget_label(r['memory_budget'])})" if r.get("memory_budget") else ""),
                     size_label(r), r["bounces"], ms(r.get("device_ms")),
                     gib(r.get("device_bytes")) if r.get("device_bytes") else "—",
                     r.get("launches", "—"),
                     ms(r.get("longest_launch_ms")),
                     ("error: " + failure_kind(r) if r.get("status") == "error"
                      else r.get("end") or r.get("status", "")).replace("|", "/")])
    doc += ["<details><summary>Every limits cell</summary>", "",
            table(["Pipeline", "Resolution", "B", "Device ms", "Global memory", "Launches",
                   "Longest launch ms", "How it ended"], body),
            "", "</details>", ""]
    return doc


def write_readme(out, doc):
    """Writes a result set's README and, when the set lies in results/, the index beside it."""
    with open(out, "w") as f:
        f.write("\n".join(doc))
    print(f"results-readme: wrote {out}")
    results = os.path.dirname(os.path.dirname(os.path.abspath(out)))
    if os.path.basename(results) == "results":
        write_index(results)


def device_rows(meta):
    """The device, platform and driver rows that head every result README."""
    return [["Device", f"{meta.get('device')} ({meta.get('device_type')}, "
                       f"{meta.get('compute_units')} compute units)"],
            ["Platform", f"{meta.get('platform')} — {meta.get('device_version')}"],
            ["Driver", meta.get("driver")]]


def limits_only_doc(data, limit_docs):
    meta = clean_meta(data["meta"], data["rows"])
    return [f"# Results: {meta.get('device')}",
            "",
            "Generated by `scripts/results-readme.py`; do not edit by hand.",
            "",
            table(["", ""], device_rows(meta)),
            ""] + limit_docs


def sweep_files(folder):
    """The sweep JSONs (written by rtlab sweep: "meta" and "rows") in a result-set folder."""
    out = []
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".json"):
            continue
        try:
            with open(os.path.join(folder, name)) as f:
                data = json.load(f)
        except (OSError, ValueError):
            continue
        if isinstance(data, dict) and "meta" in data and "rows" in data:
            out.append((name, data))
    return out


def write_index(results):
    doc = ["# Result sets",
           "",
           "Generated by `scripts/results-readme.py` from the sweep JSON in each folder; do not "
           "edit by hand. Each folder holds the CSV, the JSON, five charts and its own README with "
           "the full tables. A wave/mega ratio above 1 means the megakernel is faster. A `limits` "
           "sweep (bench/sweeps/limits) says how far each pipeline goes on that device.",
           ""]
    for slug in sorted(os.listdir(results)):
        folder = os.path.join(results, slug)
        if not os.path.isdir(folder):
            continue
        for name, data in sweep_files(folder):
            meta = clean_meta(data["meta"], data["rows"])
            rows = [r for r in data["rows"] if r.get("status") == "ok"]
            winners, _ = winner_table(rows)
            is_limits = bool(in_group(data["rows"], "limits"))
            doc += [f"## [{meta.get('device')}]({slug}/README.md) — sweep `{meta.get('sweep')}`",
                    "",
                    f"{meta.get('platform')}, driver {meta.get('driver')}; commit "
                    f"`{meta.get('commit')}`; {meta.get('measured')} of {meta.get('cells')} cells"
                    + (f" ran, {meta.get('failed')} failed, {meta.get('not_run', 0)} not run"
                       if is_limits else "")
                    + f"; measured {meta.get('started')}. Data: [`{name}`]({slug}/{name}).",
                    "",
                    limits_summary(data["rows"]) if is_limits else winners,
                    ""]
            if is_limits:
                if os.path.exists(os.path.join(folder, "limits.png")):
                    doc += [f"![Limits on {meta.get('device')}]({slug}/limits.png)", ""]
            elif os.path.exists(os.path.join(folder, "speed-vs-accuracy.png")):
                doc += [f"![Speed against accuracy on {meta.get('device')}]"
                        f"({slug}/speed-vs-accuracy.png)", ""]
    with open(os.path.join(results, "README.md"), "w") as f:
        f.write("\n".join(doc))
    print(f"results-readme: wrote {os.path.join(results, 'README.md')}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json", nargs="?")
    ap.add_argument("--out", help="README path [README.md beside the JSON]")
    ap.add_argument("--index", metavar="RESULTS", help="only rewrite RESULTS/README.md")
    args = ap.parse_args()
    if args.index:
        write_index(args.index)
        return 0
    if not args.json:
        ap.error("give a sweep JSON, or --index RESULTS")
    with open(args.json) as f:
        given = json.load(f)
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.json)), "README.md")
    here = os.path.dirname(os.path.abspath(out))
    # A folder holds one result set per device, possibly from several sweeps (`cpu` and `limits`):
    # the README covers all of them, the given JSON as it is now.
    sweeps = [(os.path.abspath(os.path.join(here, n)), d) for n, d in sweep_files(here)]
    sweeps = [(p, d) for p, d in sweeps if p != os.path.abspath(args.json)]
    sweeps.insert(0, (os.path.abspath(args.json), given))
    limits = [(p, d) for p, d in sweeps if in_group(d["rows"], "limits")]
    others = [(p, d) for p, d in sweeps
              if any(set(r.get("groups", [])) - {"limits"} for r in d["rows"])]
    limit_docs = []
    for path, d in limits:
        limit_docs += limits_section(d, os.path.relpath(path, here),
                                     os.path.exists(os.path.join(here, "limits.png")))
    if not others:
        write_readme(out, limits_only_doc(given, limit_docs))
        return 0
    main_path, data = others[0]
    meta, all_rows = clean_meta(data["meta"], data["rows"]), data["rows"]
    rows = [r for r in all_rows if r.get("status") == "ok"]
    failed = [r for r in all_rows if r.get("status") != "ok"]
    s = meta.get("settings", {})
    ref = s.get("reference", {})
    json_rel = os.path.relpath(main_path, here)
    csv_rel = os.path.splitext(json_rel)[0] + ".csv"

    winners, by_scene = winner_table(rows)
    doc = [f"# Results: {meta.get('device')}",
           "",
           "Generated by `scripts/results-readme.py` from "
           f"[`{json_rel}`]({json_rel}) (also [`{csv_rel}`]({csv_rel})); do not edit by hand.",
           "",
           table(["", ""], [
               *device_rows(meta),
               ["Commit", f"`{meta.get('commit')}`"],
               ["Sweep", f"`{meta.get('config_file')}` ({meta.get('measured')} of "
                         f"{meta.get('cells')} cells measured, {meta.get('failed')} failed"
                         f"{'' if meta.get('complete', True) else ', stopped by its time limit'})"],
               ["Measured", f"{meta.get('started')} to {meta.get('finished')}; host load "
                            f"average {meta.get('host_load_start', '?')} at the start, "
                            f"{meta.get('host_load_end', '?')} at the end"
                            + (f", imported from {meta['imported_from']}"
                               if meta.get("imported_from") else "")],
               ["Timing", f"device ms = sum of a frame's kernels by OpenCL profiling events; "
                          f"median of {s.get('repeats')} frames after {s.get('warmup')} "
                          f"warm-up frames; rays counted in a separate untimed frame"],
               ["Reference", f"CPU, double precision, B={ref.get('bounces')}, "
                             f"{ref.get('shadow_samples')} shadow samples, aa={ref.get('aa')} "
                             f"(error: RMSE of linear values clamped to [0, 1])"],
           ]),
           "",
           "## Which pipeline wins",
           "",
           "Geometric mean over every setting the sweep measured on both pipelines; a "
           "wave/mega ratio above 1 means the megakernel is faster.",
           "",
           winners,
           ""]
    for scene, ratios in by_scene.items():
        doc.append(f"- **{scene}**: {verdict(geomean(ratios))} "
                   f"(wave/mega {geomean(ratios):.2f} over {len(ratios)} settings).")
    doc += ["",
            "## Scenes (report table: objects, spheres, triangles, acceleration, resolution)",
            "",
            scene_table(rows),
            "",
            "## Time and memory against the bounce limit",
            "",
            bounce_table(rows),
            "",
            "## Acceleration structures",
            "",
            accel_table(rows),
            "",
            "## Speed against accuracy: the Pareto front",
            "",
            "Settings no other setting beats on both device time and error.",
            "",
            pareto_table(rows),
            "",
            "## Charts",
            ""]
    for png, title in CHARTS:
        doc += [f"### {title}", "", f"![{title}]({png})", ""]
    if failed:
        doc += ["## Cells that could not be measured", ""]
        doc += [table(["Scene", "Pipeline", "Resolution", "B", "Accel", "Reason"],
                      [[r["scene"], r["pipeline"], f"{r['width']}×{r['height']}", r["bounces"],
                        r["accel"], r.get("error", "").replace("|", "/")] for r in failed]), ""]
    doc += limit_docs
    write_readme(out, doc)


if __name__ == "__main__":
    sys.exit(main())
