"""rtlab — the register study's table (scripts/register-study): for each build variant of the
weighted megakernel, the registers and spills NVIDIA's build log gives for Megakernel_Render, the
occupancy they allow, and the device time on each scene against the plain build. A time whose
median is within the frame spread of the plain build's is a tie (tools/rtlab_report/compare.py).

  tools/rtlab_report/register_study.py DIR      (DIR holds one folder of sweep rows per variant)
Standard library only.
"""
import json
import math
import pathlib
import sys

from .compare import tied

ORDER = ["plain", "packed-stack", "outline-query", "outline-surface", "outline-shadows",
         "outline-step", "outline-pattern", "cap-128", "cap-96", "cap-64", "query-cap-128"]
KERNEL = "Megakernel_Render"


def occupancy(registers, group_warps=4, regs_per_sm=65536, max_warps=64, granule=8):
    """Warps a multiprocessor holds at this many registers a lane (allocated `granule` at a
    time), in whole work-groups of `group_warps` warps, and that over the most it can hold."""
    per_warp = math.ceil(registers / granule) * granule * 32
    warps = min(max_warps, regs_per_sm // per_warp) // group_warps * group_warps
    return warps, warps / max_warps


def load(folder):
    rows = []
    path = folder / "rows.jsonl"
    if path.exists():
        rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return rows


def main(argv=None):
    root = pathlib.Path((argv or sys.argv[1:])[0])
    variants = {d.name: load(d) for d in sorted(root.iterdir()) if (d / "rows.jsonl").exists()}
    names = [n for n in ORDER if n in variants] + sorted(set(variants) - set(ORDER))
    if "plain" not in variants:
        sys.exit("register_study: no plain build's rows to compare with")
    scenes = [r["scene"] for r in variants["plain"] if r.get("status") == "ok"]
    plain = {r["scene"]: r for r in variants["plain"] if r.get("status") == "ok"}
    first = variants["plain"][0] if variants["plain"] else {}
    print(f"# The weighted megakernel's registers, build by build\n")
    print(f"{first.get('device', '?')}, driver {first.get('driver', '?')}, commit "
          f"{first.get('commit', '?')}, {first.get('width')}x{first.get('height')}, "
          f"B = {first.get('bounces')}, accel {first.get('accel')}, median of "
          f"{first.get('repeats')} frames after {first.get('warmup')} warm-up frames; registers "
          f"from the build log; occupancy derived (65,536 registers a multiprocessor, 64 warps, "
          f"8 registers a lane at a time, work-groups of 4 warps). Times in ms; ×: against the "
          f"plain build, *tie* where the medians differ by no more than the larger frame spread (tools/rtlab_report/compare.py).\n")
    head = ["variant", "options", "registers", "spills st/ld", "warps/SM", "occupancy"] + scenes
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for name in names:
        rows = {r["scene"]: r for r in variants[name]}
        res = {}
        for r in variants[name]:
            res.update(r.get("kernel_resources") or {})
        regs = res.get(f"{KERNEL}.registers")
        cells = [name, "`" + (next(iter(rows.values()), {}).get("cl_options") or "-") + "`"]
        if regs is None:
            cells += ["?", "?", "?", "?"]
        else:
            warps, occ = occupancy(regs)
            cells += [f"{regs:.0f}", f"{res.get(KERNEL + '.spill_stores', 0):.0f}/"
                      f"{res.get(KERNEL + '.spill_loads', 0):.0f}", str(warps), f"{100 * occ:.0f}%"]
        for s in scenes:
            r, p = rows.get(s), plain[s]
            if not r or r.get("status") != "ok":
                cells.append(f"{(r or {}).get('status', 'not run')}")
                continue
            ratio = r["device_ms"] / p["device_ms"]
            overlap = tied(r, p)
            text = f"{r['device_ms']:.3f}"
            if name != "plain":
                text += " (tie)" if overlap else f" ({ratio:.2f}×)"
            cells.append(text)
        print("| " + " | ".join(cells) + " |")

