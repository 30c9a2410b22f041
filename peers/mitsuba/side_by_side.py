#!/usr/bin/env python3
"""rtlab's designs against the Mitsuba peer's two Dr.Jit modes, per scene (issue 53, items 3 and 4,
and its acceptance: rtlab's fastest design against Dr.Jit's faster mode, the ratio).

Reads the peer's timing rows (peers/mitsuba/timing.py, gpu-run.sh's peer-rows.jsonl) and rtlab's
sweep rows (rtlab-bench --sweep peer-mitsuba --out DIR: DIR/rows.jsonl), matches them by scene
name, size and bounce limit, and writes per scene: rtlab's fastest design and its device time,
the fastest megakernel-family design (mega tree/weighted, persist) and wavefront-family design
(wave, queue), the peer's symbolic (megakernel) and evaluated (wavefront) times, the ratio of
Dr.Jit's faster mode to rtlab's fastest (> 1: rtlab is faster), whether each system's
megakernel beats its own wavefront (the crossover question), and the rays of both (the same
work, or the difference in percent). Markdown on standard output, the rows as JSON with --json,
a chart with --chart (matplotlib; log scale, one group of bars per scene).

  side_by_side.py PEER_ROWS.jsonl RTLAB_ROWS.jsonl [--json out.json] [--chart out.png]
Standard library (and matplotlib for --chart).
"""
import argparse
import json
import os
import sys

MEGA = ("mega", "persist")  # rtlab's megakernel family; wave and queue are wavefronts


def design(r):
    p = r.get("pipeline", "?")
    if p == "mega":
        return f"mega {r.get('layout', 'tree')}"
    if p == "persist":
        return "persist"
    return p


def load(path):
    with open(path) as f:
        return [json.loads(l) for l in f if l.strip()]


def key(scene, w, h, b):
    return (os.path.basename(str(scene)), int(w), int(h), int(b))


def join(peer_rows, rtlab_rows):
    rt = {}
    for r in rtlab_rows:
        if r.get("status", "ok") not in ("ok", "ran") and r.get("end") != "ran":
            continue
        if not r.get("device_ms"):
            continue
        k = key(r["scene"], r["width"], r["height"], r["bounces"])
        rt.setdefault(k, []).append(r)
    peer = {}
    for r in peer_rows:
        if "median_ms" not in r:
            continue
        k = key(r["scene"], r["width"], r["height"], r["bounces"])
        peer.setdefault(k, {})[r["mode"]] = r
    out = []
    for k in sorted(set(rt) | set(peer), key=lambda k: (k[0].startswith("map"), k)):
        rows, modes = rt.get(k, []), peer.get(k, {})
        row = {"scene": k[0], "width": k[1], "height": k[2], "bounces": k[3]}
        if rows:
            best = min(rows, key=lambda r: r["device_ms"])
            row.update(rtlab_best=design(best), rtlab_best_ms=best["device_ms"],
                       rtlab_rays=sum((best.get("rays") or {}).values()) or None,
                       rtlab_designs={design(r): round(r["device_ms"], 4) for r in rows})
            mega = [r for r in rows if r.get("pipeline") in MEGA]
            wave = [r for r in rows if r.get("pipeline") not in MEGA]
            if mega:
                m = min(mega, key=lambda r: r["device_ms"])
                row.update(rtlab_mega=design(m), rtlab_mega_ms=m["device_ms"])
            if wave:
                w = min(wave, key=lambda r: r["device_ms"])
                row.update(rtlab_wave=design(w), rtlab_wave_ms=w["device_ms"])
        for mode in ("symbolic", "evaluated"):
            if mode in modes:
                row[f"peer_{mode}_ms"] = modes[mode]["median_ms"]
                row[f"peer_{mode}_compile_ms"] = modes[mode].get("compile_ms")
                row["peer_rays"] = (modes[mode].get("rays") or {}).get("total")
        pm = [row[f"peer_{m}_ms"] for m in ("symbolic", "evaluated") if f"peer_{m}_ms" in row]
        if pm:
            row["peer_best_ms"] = min(pm)
            row["peer_best"] = "symbolic" if row.get("peer_symbolic_ms") == min(pm) else "evaluated"
        if "peer_best_ms" in row and "rtlab_best_ms" in row:
            row["ratio"] = row["peer_best_ms"] / row["rtlab_best_ms"]
        if "rtlab_mega_ms" in row and "rtlab_wave_ms" in row:
            row["rtlab_megakernel_wins"] = row["rtlab_mega_ms"] < row["rtlab_wave_ms"]
        if "peer_symbolic_ms" in row and "peer_evaluated_ms" in row:
            row["peer_megakernel_wins"] = row["peer_symbolic_ms"] < row["peer_evaluated_ms"]
        if row.get("peer_rays") and row.get("rtlab_rays"):
            diff = row["peer_rays"] - row["rtlab_rays"]
            row["rays_diff_pct"] = 100.0 * diff / row["rtlab_rays"]
        out.append(row)
    return out


def fmt(v, nd=2):
    return "-" if v is None else (f"{v:.{nd}f}" if isinstance(v, float) else str(v))


def markdown(rows):
    lines = ["| scene | size | rtlab best | ms | rtlab mega / wave (ms) | Dr.Jit symbolic | "
             "Dr.Jit evaluated | Dr.Jit best / rtlab best | megakernel wins: rtlab, Dr.Jit | "
             "rays (peer - rtlab) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        yn = lambda v: "-" if v is None else ("yes" if v else "no")
        lines.append(
            f"| {r['scene']} | {r['width']}x{r['height']} B={r['bounces']} | "
            f"{r.get('rtlab_best', '-')} | {fmt(r.get('rtlab_best_ms'))} | "
            f"{fmt(r.get('rtlab_mega_ms'))} / {fmt(r.get('rtlab_wave_ms'))} | "
            f"{fmt(r.get('peer_symbolic_ms'))} | {fmt(r.get('peer_evaluated_ms'))} | "
            f"{fmt(r.get('ratio'))} | {yn(r.get('rtlab_megakernel_wins'))}, "
            f"{yn(r.get('peer_megakernel_wins'))} | {fmt(r.get('rays_diff_pct'), 3)}% |")
    return "\n".join(lines)


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = [r for r in rows if "rtlab_best_ms" in r or "peer_best_ms" in r]
    series = [("rtlab fastest", "rtlab_best_ms"), ("rtlab megakernel", "rtlab_mega_ms"),
              ("rtlab wavefront", "rtlab_wave_ms"), ("Dr.Jit symbolic", "peer_symbolic_ms"),
              ("Dr.Jit evaluated", "peer_evaluated_ms")]
    fig, ax = plt.subplots(figsize=(max(8, 0.6 * len(rows) + 2), 5))
    width = 0.8 / len(series)
    for i, (label, k) in enumerate(series):
        xs = [j + i * width for j, r in enumerate(rows) if r.get(k)]
        ys = [r[k] for r in rows if r.get(k)]
        ax.bar(xs, ys, width, label=label)
    ax.set_yscale("log")
    ax.set_ylabel("device ms per frame (median)")
    ax.set_xticks([j + 0.4 - width / 2 for j in range(len(rows))])
    ax.set_xticklabels([r["scene"].replace("map-", "") for r in rows], rotation=60, ha="right",
                       fontsize=8)
    ax.legend(fontsize=8)
    ax.set_title("rtlab's designs against Mitsuba 3 / Dr.Jit's modes (issue 53)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("peer_rows")
    ap.add_argument("rtlab_rows")
    ap.add_argument("--json")
    ap.add_argument("--chart")
    a = ap.parse_args(argv)
    rows = join(load(a.peer_rows), load(a.rtlab_rows))
    print(markdown(rows))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    if a.chart:
        chart(rows, a.chart)
    return 0


if __name__ == "__main__":
    sys.exit(main())
