"""The Limits section of a result set's README (results_readme.py): how far each pipeline goes
in the `limits` sweep (bench/sweeps/limits): per series the last setting that ran, where its
global ray tree first tiled, and the first setting that failed and how (the rows' failure field).
Standard library only.
"""
from .readme_format import clean_meta, gib, ms, size_label, table, tree_text
from .sweep_rows import FAILURES, Series, failure, in_group, limit_series, setting


def setting_of(r, axis):
    return f"B={r['bounces']}" if axis == "bounces" else size_label(r)


def how_text(series):
    how = series["how"]
    if how is None:
        return "— (every setting ran)"
    if how == "skipped":
        # Why it was not run (an earlier failure, or a frame past max-frame-s) in the sweep's words.
        reason = series["stop"].get("skip_reason", "")
        return f"not run: {reason.split('(', 1)[-1].split(')')[0]}" if "(" in reason else "not run"
    return f"error: {FAILURES.get(how, how)}"


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
            tiles = f"{setting_of(tiled, axis)} ({tree_text({0: tiled})})"
        body.append([s["scene"], s["label"], f"{'bounce limit' if axis == 'bounces' else 'resolution'} "
                     f"{s['fixed']}", lr, tiles, setting_of(stop, axis) if stop else "—", how_text(s)])
    return table(["Scene", "Pipeline", "Axis (fixed)", "Last that ran: device ms, global memory, "
                  "launches", "Global ray tree tiled from", "First failure", "How it failed"], body)


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
        if failure(r) not in ("", "skipped"):
            errors.setdefault(r.get("error", ""), []).append(r)
    # Each pair of frames compared is recorded on both rows: count it once.
    compared = list({(setting(r), r.get("layout"), frozenset((r["pipeline"],
                      r["image_compared_with"]))): r for r in rows
                     if r.get("image_compared_with") and "image_max_diff" in r}.values())
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
            where = ", ".join(f"{Series(rows).label(Series(rows).key(r))} {size_label(r)} "
                              f"B={r['bounces']}" for r in rs[:4])
            doc.append(f"- {where}{' …' if len(rs) > 4 else ''}: `{msg}`")
        doc.append("")
    if compared:
        doc.append(f"Frames of two pipelines were compared at the {len(compared)} settings both ran: "
                   + ("bit-identical at every one." if not differing else
                      f"{len(differing)} differ (largest |difference| "
                      f"{max(r['image_max_diff'] for r in differing):g}).")
                   + (" No frame has a NaN or infinite pixel." if not nonfinite else
                      f" {len(nonfinite)} frames have NaN or infinite pixels."))
        doc.append("")
    timed = [r for r in rows if failure(r) == "" and r.get("longest_launch_ms") is not None]
    series = Series(rows)
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
                       f"{ms(worst['longest_launch_ms'])} ms, {series.label(series.key(worst))} "
                       f"{size_label(worst)} B={worst['bounces']}). Tiles are "
                       "planned from each row's cost measured in the earlier frames of the same "
                       "setting, aiming at 80% of the target. A launch runs over when its rows "
                       "cost more than the planner predicted from the frames before (other load "
                       f"on the machine: host load average {meta.get('host_load_start', '?')} at "
                       f"the start, {meta.get('host_load_end', '?')} at the end; or, before "
                       "commit ed93f1e, a planning error: a measured tile cut at an even share "
                       "per row or column), or when one pixel's work alone exceeds the target: "
                       "the megakernel and the tree wavefront trace a pixel's whole ray tree in "
                       "one work-item, so no launch ends before its costliest pixel.")
        doc.append("")
    if chart_exists:
        doc += ["![Limits: time, memory and longest launch against bounce limit and resolution]"
                "(limits.png)", ""]
    body = []
    for r in rows:
        kind = failure(r)
        ended = "ran" if kind == "" else "not run" if kind == "skipped" else \
            f"error: {FAILURES.get(kind, kind)}"
        body.append([series.label(series.key(r)), size_label(r), r["bounces"],
                     ms(r.get("device_ms")),
                     gib(r.get("device_bytes")) if r.get("device_bytes") else "—",
                     tree_text({0: r}) if kind == "" else "—", r.get("launches", "—"),
                     ms(r.get("longest_launch_ms")), ended])
    doc += ["<details><summary>Every limits cell</summary>", "",
            table(["Pipeline", "Resolution", "B", "Device ms", "Global memory",
                   "Global ray tree", "Launches", "Longest launch ms", "How it ended"], body),
            "", "</details>", ""]
    return doc
