#!/usr/bin/python3
"""Writes results/<device-slug>/README.md from the JSON of a sweep (`rtlab sweep` runs this).

Usage: /usr/bin/python3 scripts/results-readme.py results/<device-slug>/<sweep>.json [--out FILE]

The README holds the tables the report's results chapter left empty (per scene: number of
objects, spheres, triangles, acceleration structures, resolution, and the two pipelines' times),
which pipeline wins on each scene and by what ratio, the time-against-bounce-limit and
acceleration tables, the Pareto front of speed against accuracy, failed cells, and the charts.
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
           "the full tables. A wave/mega ratio above 1 means the megakernel is faster.",
           ""]
    for slug in sorted(os.listdir(results)):
        folder = os.path.join(results, slug)
        if not os.path.isdir(folder):
            continue
        for name, data in sweep_files(folder):
            meta = data["meta"]
            rows = [r for r in data["rows"] if r.get("status") == "ok"]
            winners, _ = winner_table(rows)
            doc += [f"## [{meta.get('device')}]({slug}/README.md) — sweep `{meta.get('sweep')}`",
                    "",
                    f"{meta.get('platform')}, driver {meta.get('driver')}; commit "
                    f"`{meta.get('commit')}`; {meta.get('measured')} of {meta.get('cells')} cells; "
                    f"measured {meta.get('started')}. Data: [`{name}`]({slug}/{name}).",
                    "",
                    winners,
                    ""]
            if os.path.exists(os.path.join(folder, "speed-vs-accuracy.png")):
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
        data = json.load(f)
    meta, all_rows = data["meta"], data["rows"]
    rows = [r for r in all_rows if r.get("status") == "ok"]
    failed = [r for r in all_rows if r.get("status") != "ok"]
    s = meta.get("settings", {})
    ref = s.get("reference", {})
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.json)), "README.md")
    here = os.path.dirname(os.path.abspath(out))
    json_rel = os.path.relpath(os.path.abspath(args.json), here)
    csv_rel = os.path.splitext(json_rel)[0] + ".csv"

    winners, by_scene = winner_table(rows)
    doc = [f"# Results: {meta.get('device')}",
           "",
           "Generated by `scripts/results-readme.py` from "
           f"[`{json_rel}`]({json_rel}) (also [`{csv_rel}`]({csv_rel})); do not edit by hand.",
           "",
           table(["", ""], [
               ["Device", f"{meta.get('device')} ({meta.get('device_type')}, "
                          f"{meta.get('compute_units')} compute units)"],
               ["Platform", f"{meta.get('platform')} — {meta.get('device_version')}"],
               ["Driver", meta.get("driver")],
               ["Commit", f"`{meta.get('commit')}`"],
               ["Sweep", f"`{meta.get('config_file')}` ({meta.get('measured')} of "
                         f"{meta.get('cells')} cells measured, {meta.get('failed')} failed"
                         f"{'' if meta.get('complete', True) else ', stopped by its time limit'})"],
               ["Measured", f"{meta.get('started')} to {meta.get('finished')}; host load "
                            f"average {meta.get('host_load_start', '?')} at the start, "
                            f"{meta.get('host_load_end', '?')} at the end"
                            + (f", imported from `{meta['imported_from']}`"
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
    with open(out, "w") as f:
        f.write("\n".join(doc))
    print(f"results-readme: wrote {out}")
    results = os.path.dirname(here)
    if os.path.basename(results) == "results":
        write_index(results)


if __name__ == "__main__":
    sys.exit(main())
