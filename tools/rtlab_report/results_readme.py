"""Writes results/<device-slug>/README.md from the JSON of a sweep (`rtlab sweep` runs this).

Usage: python3 -m rtlab_report readme results/<device-slug>/<sweep>.json
                                                  [--out FILE] [--index]
       python3 -m rtlab_report readme results          (the index only)

The README holds the tables the report's results chapter left empty (per scene: number of
objects, spheres, triangles, acceleration structures, resolution, and every pipeline's time),
which pipeline wins on each scene and by what ratio to the fastest, the
time-against-bounce-limit and acceleration tables, the Pareto front of speed against accuracy,
failed cells, and the charts.
A folder may hold several sweeps of one device: the README covers them all, the `limits` sweep
(bench/sweeps/limits) in its own section (per pipeline the last setting that ran, its time and
memory, and how the first failing one failed). Where rtlab-roofline's roofline.json lies in the
folder, each frame is set against its memory floor (tools/rtlab_report/readme_floor.py).
Every figure comes from the JSON; the header says which device, driver, commit and settings.

The pipelines, their titles and layouts come from the rows (sweep_rows.py), so a new pipeline
needs no change here. With --index, results/README.md (the tracked index of every result set:
device, commit, which pipeline wins on each scene, the speed-against-accuracy chart, and every
folder under results/ with the commits its data records) is rewritten too; only committing a
result set should ask for that, never a user's own sweep.
Standard library only.
"""
import argparse
import json
import os
import re
import sys

from .compare import PARETO_RTOL, agreement_text, error_agreement, pareto
from .readme_format import accel_label, clean_meta, ms, size_label, table, tree_text
from .readme_crossover import crossover_section
from .readme_floor import floor_section
from .readme_limits import limits_section
from .readme_winners import fastest_text, winner_table
from . import results_index
from .sweep_rows import Series, by_setting, failure, in_group

CHARTS = [("time-vs-resolution.png", "Frame time against resolution"),
          ("time-vs-bounces.png", "Frame time against bounce limit"),
          ("memory-vs-bounces.png", "Device memory against bounce limit"),
          ("kernel-breakdown.png", "Device time per kernel"),
          ("speed-vs-accuracy.png", "Speed against accuracy, Pareto front marked")]
RATIO_TEXT = ("Times are compared per setting with the fastest series (pipeline, and layout where "
              "one pipeline ran several) measured at that setting: 1.00 is the fastest, 2.00 "
              "twice its time. Only settings where every series ran are counted; where one ran in "
              "fewer, the text says in how many. Two times whose medians differ by no more than "
              "the larger of their frame spreads (slowest minus fastest timed frame) are a tie, "
              "not a win (tools/rtlab_report/compare.py). A scene's winner has the lowest geometric mean of "
              "the ratio, which need not be the series fastest in most settings (small losses, "
              "large wins); means within the cells' median frame spread of it are level with it.")


def scene_table(rows):
    """Report table: per scene and resolution, object counts and every series' time."""
    chosen = in_group(rows, "resolution") or rows
    series = Series(chosen)
    body = []
    for k, cells in by_setting(chosen, series):
        r = next(iter(cells.values()))
        info = r["scene_info"]
        body.append([r["scene"], info["objects"], info["spheres"], info["triangles"],
                     accel_label(r), size_label(r),
                     f"B={r['bounces']} s={r['shadow_samples']} aa={r['aa']}"]
                    + [ms(cells[s]["device_ms"]) if s in cells else "—" for s in series.keys]
                    + [fastest_text(cells, series)])
    return table(["Scene", "No. objects", "Spheres", "Triangles", "Acceleration structures",
                  "Resolution", "Settings"] + [f"{series.label(s)} ms" for s in series.keys]
                 + ["Fastest (others: time / fastest)"], body)


def bounce_table(rows):
    chosen = in_group(rows, "bounces")
    series = Series(chosen)
    body = []
    for k, cells in by_setting(chosen, series):
        r = next(iter(cells.values()))
        used = [c["tree_used"] for c in cells.values() if c.get("tree_used") is not None]
        body.append([r["scene"], size_label(r), r["bounces"], r["tree_nodes"]]
                    + [ms(cells[s]["device_ms"]) if s in cells else "—" for s in series.keys]
                    + [f"{cells[s]['device_bytes'] / 2**20:.1f}" if s in cells else "—"
                       for s in series.keys]
                    + [fastest_text(cells, series), tree_text(cells),
                       "—" if not used else f"{100 * used[0]:.1f}%"])
    return table(["Scene", "Resolution", "B", "Tree nodes N"]
                 + [f"{series.label(s)} ms" for s in series.keys]
                 + [f"{series.label(s)} MiB" for s in series.keys]
                 + ["Fastest (others: time / fastest)", "Global ray tree", "Tree slots used"],
                 body)


def accel_table(rows):
    """Each structure against brute force on the same view, per pixel (sizes may differ)."""
    chosen = [r for r in in_group(rows, "accel") if r["accel"] != "-"]
    series = Series(chosen)
    base = {(r["scene"], series.key(r), r["bounces"]): r for r in chosen if r["accel"] == "none"}
    body = []
    for r in chosen:
        b = base.get((r["scene"], series.key(r), r["bounces"]))
        ratio = "—"
        if b:
            per_px = (r["device_ms"] / (r["width"] * r["height"])) / (
                b["device_ms"] / (b["width"] * b["height"]))
            ratio = f"{per_px:.4g}"
        body.append([r["scene"], series.label(series.key(r)), size_label(r), r["bounces"],
                     r["accel"], ms(r["device_ms"]), ratio])
    return table(["Scene", "Pipeline", "Resolution", "B", "Accel", "Device ms",
                  "accel/none (time per pixel)"], body)


def pareto_table(rows):
    scored = [r for r in in_group(rows, "accuracy") if r.get("rmse") is not None]
    series = Series(scored) if scored else None
    body = []
    for scene in dict.fromkeys(r["scene"] for r in scored):
        points = [(r["device_ms"], r["rmse"], r) for r in scored if r["scene"] == scene]
        for _, _, r in pareto(points):
            body.append([scene, series.label(series.key(r)), r["bounces"],
                         r["shadow_samples"], r["aa"], ms(r["device_ms"]),
                         f"{r['rmse']:.4f}", f"{r['psnr_db']:.1f}"])
    out = table(["Scene", "Pipeline", "B", "Shadow samples", "AA", "Device ms", "RMSE",
                 "PSNR dB"], body)
    # How alike the designs' errors are, exact equality apart from equality after rounding.
    agree = agreement_text(error_agreement(scored))
    if agree:
        out = agree + "\n\n" + out
    # A frame with a NaN or infinite pixel has no error score (rmse is null): name each one.
    broken = [r for r in in_group(rows, "accuracy") if r.get("nonfinite_pixels")]
    for r in broken:
        out += (f"\n\n**{r['scene']} {r['pipeline']} B={r['bounces']}: "
                f"{r['nonfinite_pixels']} non-finite pixel(s); no accuracy score.**")
    return out

def write_readme(out, doc, index=False):
    """Writes a result set's README and, when asked (--index: committing result sets), the index
    of the folder above it. A user's own sweep must not rewrite the tracked results/README.md."""
    with open(out, "w") as f:
        f.write("\n".join(doc))
    print(f"results-readme: wrote {out}")
    if index:
        write_index(os.path.dirname(os.path.dirname(os.path.abspath(out))))


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
            "Generated by `tools/rtlab_report/results_readme.py`; do not edit by hand.",
            "",
            table(["", ""], device_rows(meta)),
            ""] + limit_docs


def read_sweep(path):
    """The sweep a file holds (written by rtlab sweep: "meta" and "rows"), else None."""
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and "meta" in data and "rows" in data else None


def sweep_files(folder):
    """The sweep JSONs (written by rtlab sweep: "meta" and "rows") in a result-set folder."""
    out = []
    for name in sorted(os.listdir(folder)):
        data = read_sweep(os.path.join(folder, name)) if name.endswith(".json") else None
        if data is not None:
            out.append((name, data))
    return out


def write_index(results):
    """results/README.md: the published set of each device kind (a folder at the top), the
    experiments that led there (a page each, their raw files archived), and where each lies.
    results_check.py holds it complete."""
    doc = ["# Results",
           "",
           "Generated by `python3 tools/rtlab_report readme results` from the data in each folder; "
           "do not edit by hand (`python3 tools/rtlab_report check-results .` and "
           "tests/python/test_results_index.py keep it complete).",
           "",
           "- One folder a device kind: its **published set**, the sweeps (`NAME.json`, "
           "`NAME.csv`, the device logs), their charts and a README with the full tables.",
           "- [`experiments/`](experiments/): one page an **experiment** that led there: the "
           "question, the setting, the commits its data records, the finding, and where its raw "
           "data lies.",
           "- [`archive/`](archive/): the raw files of each experiment, one `NAME.tar.xz` each "
           "(`tar -xJf results/archive/NAME.tar.xz` puts them back where they were). Patch "
           "files are not kept: the code each experiment ran is in git history. A new "
           "experiment, imported elsewhere (`RTLAB_RESULTS_DIR=/tmp/exp scripts/gpu-sweep.sh "
           "import ...`), is filed with `python3 tools/rtlab_report experiment /tmp/exp NAME "
           "DEVICE-SLUG --into results`, then this index rewritten.",
           "",
           "Wins and ties: " + RATIO_TEXT,
           "",
           "## Published sets",
           "",
           "A set is meant to be measured at one commit; where a folder's sweeps record more "
           "than one, the table says so.",
           ""]
    body = []
    for slug in sorted(e for e in os.listdir(results)
                       if os.path.isdir(os.path.join(results, e))
                       and e not in ("experiments", "archive")):
        folder = os.path.join(results, slug)
        sweeps, device, commits = [], slug, set()
        for name, data in sweep_files(folder):
            meta = clean_meta(data["meta"], data["rows"])
            device = meta.get("device") or device
            commit = str(meta.get("commit", "?"))[:7]
            commits.add(commit)
            sweeps.append(f"[`{name[:-5]}`]({slug}/{name}) at `{commit}`, "
                          f"{meta.get('measured')} of {meta.get('cells')} cells")
        one = "one commit" if len(commits) == 1 else f"**{len(commits)} commits**"
        body.append([f"[`{slug}`]({slug}/README.md)", device, "; ".join(sweeps) or "—", one])
    doc += [table(["Folder", "Device", "Sweeps", "At"], body), ""]
    doc += experiments_table(results)
    with open(os.path.join(results, "README.md"), "w") as f:
        f.write("\n".join(doc))
    print(f"results-readme: wrote {os.path.join(results, 'README.md')}")


def experiments_table(results):
    """Every experiment page, its device, the commits its archive's data records and the
    archive's size."""
    folder = os.path.join(results, "experiments")
    body = []
    for name in sorted(n[:-3] for n in os.listdir(folder) if n.endswith(".md")) \
            if os.path.isdir(folder) else []:
        page = os.path.join(folder, name + ".md")
        with open(page) as f:
            text = f.read()
        title = next((line.lstrip("#").strip() for line in text.splitlines()
                      if line.startswith("#")), name).replace("|", "/")
        device = re.search(r"\*\*Device\*\*: \[?`([^`]+)`", text)
        archive = results_index.page_archive(page)
        commits = sorted({c[:7] for c in results_index.archive_commits(archive)}) \
            if archive else []
        size = (f"[`{os.path.basename(archive)}`](archive/{os.path.basename(archive)}), "
                f"{os.path.getsize(archive) // 1024 or 1} KiB"
                if archive and os.path.exists(archive) else "—")
        body.append([f"[{title}](experiments/{name}.md)", f"`{device.group(1)}`" if device else "?",
                     ", ".join(f"`{c}`" for c in commits) or "—", size])
    return ["## Experiments",
            "",
            f"{len(body)} experiments, each summarised in one page; the commits are those its "
            "archived data records (rows, sweep metadata, the tools' logs).",
            "",
            table(["Experiment", "Device", "Commits in its data", "Raw data"], body),
            ""]


def header_table(meta, json_rel):
    s = meta.get("settings", {})
    ref = s.get("reference", {})
    return table(["", ""], [
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
                      f"(error: RMSE of linear values clamped to [0, 1])"]])


def about(here):
    """(title, paragraphs) from the folder's hand-written ABOUT.md, if it has one: what a
    generated README cannot know (why a set is split, what it continues). Its first line, a
    Markdown heading, replaces the generated title; the rest goes under the header table."""
    try:
        with open(os.path.join(here, "ABOUT.md")) as f:
            lines = f.read().rstrip("\n").split("\n")
    except OSError:
        return None, []
    title = lines.pop(0) if lines and lines[0].startswith("# ") else None
    while lines and not lines[0].strip():
        lines.pop(0)
    return title, lines


def full_doc(main_path, data, here, limit_docs):
    """The README of a folder with a non-limits sweep: its tables, charts and failed cells, then
    the limits sections."""
    meta, all_rows = clean_meta(data["meta"], data["rows"]), data["rows"]
    rows = [r for r in all_rows if failure(r) == ""]
    failed = [r for r in all_rows if failure(r) != ""]
    json_rel = os.path.relpath(main_path, here)
    csv_rel = os.path.splitext(json_rel)[0] + ".csv"
    winners, notes = winner_table(rows)
    title, context = about(here)
    doc = [title or f"# Results: {meta.get('device')}",
           "",
           "Generated by `tools/rtlab_report/results_readme.py` from "
           f"[`{json_rel}`]({json_rel}) (also [`{csv_rel}`]({csv_rel}))"
           + (" and the folder's hand-written [`ABOUT.md`](ABOUT.md)" if title or context else "")
           + "; do not edit by hand.",
           "",
           header_table(meta, json_rel),
           ""] + ([*context, ""] if context else []) + [
           "## Which pipeline wins",
           "",
           RATIO_TEXT + " Won / tied: settings where the series was fastest beyond the frame "
           "spread / tied for fastest within it; Tied: settings with no clear winner.",
           "",
           winners,
           ""] + notes
    doc += ["",
            "## Scenes (report table: objects, spheres, triangles, acceleration, resolution)",
            "",
            scene_table(rows),
            "",
            "## Time and memory against the bounce limit",
            "",
            "MiB: global memory allocated per frame. Global ray tree: the tree a pipeline keeps "
            "in global memory, W×H×N nodes for the whole frame; when that is over the device's "
            "largest allocation (or the memory budget) the frame runs in row tiles and one "
            "tile's tree is what is allocated.",
            "",
            bounce_table(rows),
            ""]
    doc += floor_section(rows, Series, here)
    doc += ["## Acceleration structures",
            "",
            accel_table(rows),
            "",
            "## Speed against accuracy: the Pareto front",
            "",
            "Settings no other setting beats on both device time and error; an error within "
            f"{PARETO_RTOL:.0%} of a faster point's is the same accuracy (tools/rtlab_report/compare.py).",
            "",
            pareto_table(rows),
            "",
            "## Charts",
            ""]
    for png, title in CHARTS:
        if os.path.exists(os.path.join(here, png)):
            doc += [f"### {title}", "", f"![{title}]({png})", ""]
    if failed:
        series = Series(all_rows)
        doc += ["## Cells that could not be measured", ""]
        doc += [table(["Scene", "Pipeline", "Resolution", "B", "Accel", "Failure", "Message"],
                      [[r["scene"], series.label(series.key(r)), size_label(r), r["bounces"],
                        r["accel"], failure(r), r.get("error", "").replace("|", "/")]
                       for r in failed]), ""]
    return doc + limit_docs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json", nargs="?", help="a sweep JSON, or a results folder to index")
    ap.add_argument("--out", help="README path [README.md beside the JSON]")
    ap.add_argument("--index", action="store_true",
                    help="also rewrite the results index (README.md of the folder above the set)")
    args = ap.parse_args(argv)
    if args.json and os.path.isdir(args.json):
        write_index(args.json)
        return 0
    if not args.json:
        ap.error("give a sweep JSON, or a results folder to index")
    given = read_sweep(args.json)
    if given is None:
        sys.exit(f"{ap.prog}: {args.json}: not a sweep JSON (one with \"meta\" and \"rows\")")
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.json)), "README.md")
    here = os.path.dirname(os.path.abspath(out))
    # A folder holds one result set per device, possibly from several sweeps (`cpu` and `limits`):
    # the README covers all of them, the given JSON as it is now.
    sweeps = [(os.path.abspath(os.path.join(here, n)), d) for n, d in sweep_files(here)]
    sweeps = [(p, d) for p, d in sweeps if p != os.path.abspath(args.json)]
    sweeps.insert(0, (os.path.abspath(args.json), given))
    limits = [(p, d) for p, d in sweeps if in_group(d["rows"], "limits")]
    # Crossover sweeps get their own section, like limits, after the main tables.
    cross = [(p, d) for p, d in sweeps if in_group(d["rows"], "crossover")]
    others = [(p, d) for p, d in sweeps
              if any(set(r.get("groups", [])) - {"limits", "crossover"} for r in d["rows"])]
    limit_docs = []
    for path, d in cross:
        limit_docs += crossover_section(d, os.path.relpath(path, here),
                                        os.path.exists(os.path.join(here, "crossover.png")))
    for path, d in limits:
        limit_docs += limits_section(d, os.path.relpath(path, here),
                                     os.path.exists(os.path.join(here, "limits.png")))
    doc = full_doc(*others[0], here, limit_docs) if others else limits_only_doc(given, limit_docs)
    write_readme(out, doc, args.index)
    return 0

