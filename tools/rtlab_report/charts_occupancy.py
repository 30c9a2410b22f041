"""What occupancy is worth to the queue wavefront's kernels (bench/sweeps/queue-occupancy): each
stage's device time against the warps its kernel keeps resident on a multiprocessor, as
--queue-group and --queue-local-pad set them, beside the warps the persistent megakernel's one
kernel keeps.

Resident warps are estimated from what the rows recorded of each kernel (kernel_resources: the
NVIDIA build log's registers, CL_KERNEL_LOCAL_MEM_SIZE's local bytes) and the work-group size,
with the limits of NVIDIA's sm_90 (the H100 and H200): 65,536 registers a multiprocessor,
allocated 256 a warp at a time; 228 KiB of shared memory, 1 KiB of it reserved for each
resident group; at most 64 warps and 32 groups. Rows without registers (other vendors) are
left out. A stage's time is its kernels' device times (kernel_ms); the shade stage sums its
kernels and is placed at the warps of its heaviest kernel by registers.
Writes occupancy.md and occupancy.png.

Usage: python3 -m rtlab_report occupancy-charts ROWS.jsonl [--out DIR]
Needs Debian's python3-matplotlib for the chart; the table needs nothing.
"""
import argparse
import math
import os
import sys

from .charts_map import load

REGISTERS = 65536
REGISTER_UNIT = 256       # a warp's registers are allocated in units of this many
SHARED = 228 * 1024
SHARED_RESERVED = 1024    # a resident group's share the system keeps
MAX_WARPS, MAX_GROUPS = 64, 32
STAGES = [("extend", ["Queue_Extend"]), ("shadow", ["Queue_Shadow"]), ("shade", None)]


def resident_warps(registers, local_bytes, group):
    """Warps a multiprocessor of sm_90 keeps of a kernel in groups of `group` work-items."""
    warps = math.ceil(group / 32)
    per_warp = math.ceil(registers * 32 / REGISTER_UNIT) * REGISTER_UNIT
    groups = min(REGISTERS // (per_warp * warps), SHARED // (local_bytes + SHARED_RESERVED),
                 MAX_WARPS // warps, MAX_GROUPS)
    return groups * warps


def kernel_warps(row, kernel, group):
    res = row.get("kernel_resources") or {}
    regs = res.get(kernel + ".registers")
    if regs is None:
        return None
    return resident_warps(int(regs), int(res.get(kernel + ".local_bytes", 0)), group)


def shade_kernels(row):
    res = row.get("kernel_resources") or {}
    return sorted({k.split(".")[0] for k in res if k.startswith("Queue_Shade")})


def stages(row):
    """{stage: (ms, warps)} of a queue row."""
    group = row.get("options", {}).get("queue-group") or 256
    k = row.get("kernel_ms", {})
    out = {}
    for stage, kernels in STAGES:
        if stage == "shade":
            names = shade_kernels(row)
            ms = sum(v for name, v in k.items() if name.startswith("shade"))
            regs = row.get("kernel_resources") or {}
            heaviest = max(names, key=lambda n: regs.get(n + ".registers", 0), default=None)
            warps = kernel_warps(row, heaviest, group) if heaviest else None
        else:
            ms = k.get(stage, 0.0)
            warps = kernel_warps(row, kernels[0], group)
        if warps is not None and ms > 0:
            out[stage] = (ms, warps)
    return out


def persist_warps(row):
    """Warps the persistent megakernel's kernel keeps, from its registers and group size."""
    res = row.get("kernel_resources") or {}
    for kernel in ("Persistent_RenderBounce", "Persistent_RenderRegrouped", "Persistent_Render"):
        if kernel + ".registers" in res:
            lanes = row.get("options", {}).get("persistent-lanes") or (
                512 if kernel == "Persistent_RenderBounce" else 128)
            return kernel_warps(row, kernel, lanes)
    return None


def short(scene):
    return scene.split("/")[-1].replace("map-", "").replace("-m16", "")


def setting(row):
    o = row.get("options", {})
    return f"groups of {o.get('queue-group') or 256}" + (
        f", {o['queue-local-pad']} B pad" if o.get("queue-local-pad") else "")


def gather(rows):
    """{scene: {"queue": [(setting, row, stages)], "mega": row, "persist": row}}"""
    grid = {}
    for r in rows:
        if r.get("status", "ok") != "ok":
            continue
        g = grid.setdefault(r["scene"], {"queue": []})
        if r["pipeline"] == "queue":
            s = stages(r)
            if s:
                g["queue"].append((setting(r), r, s))
        elif r["pipeline"] == "mega" and r.get("layout") == "weighted":
            g["mega"] = r
        elif r["pipeline"] == "persist":
            g["persist"] = r
    return {s: g for s, g in grid.items() if g["queue"]}


def table(meta, grid, path):
    head = ["scene", "design", "ms (speed-up)"] + [
        f"{stage}: ms (warps)" for stage, _ in STAGES]
    lines = [f"# What occupancy is worth to the queue wavefront's kernels, {meta.get('device')}",
             "", f"Driver {meta.get('driver')}, commit `{meta.get('commit')}`, sweep "
             f"`{meta.get('sweep')}`; ms, median device time. Warps: resident on a "
             "multiprocessor, estimated from each kernel's registers and local memory with "
             "sm_90's limits (tools/rtlab_report/charts_occupancy.py). Speed-up: over the weighted "
             "megakernel.", "", "| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for scene, g in grid.items():
        mega = g.get("mega")
        def speed(r):
            return f"{r['device_ms']:.3f}" + (
                f" ({mega['device_ms'] / r['device_ms']:.2f}x)" if mega else "")
        if mega:
            lines.append(f"| `{short(scene)}` | weighted megakernel | {mega['device_ms']:.3f} |"
                         + " |" * len(STAGES))
        if "persist" in g:
            w = persist_warps(g["persist"])
            lines.append(f"| `{short(scene)}` | persistent megakernel | {speed(g['persist'])} |"
                         + f" one kernel: {w if w is not None else '?'} warps |" + " |" *
                         (len(STAGES) - 1))
        for label, r, s in g["queue"]:
            cols = [f"`{short(scene)}`", "queue, " + label, speed(r)] + [
                f"{s[st][0]:.2f} ({s[st][1]})" if st in s else "—" for st, _ in STAGES]
            lines.append("| " + " | ".join(cols) + " |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def chart(meta, grid, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .chart_style import MARKERS, figure, legend_row

    fig, panels, legend_ax = figure(
        meta, "The queue's stages against the warps their kernels keep on a multiprocessor, in "
        "their time at the defaults (filled and joined: local memory padded, the same L1 left; "
        "hollow: not padded; dotted: the persistent megakernel's one kernel)", len(STAGES),
        cols=3, panel=(4.2, 3.4))
    handles, labels = [], []
    persist = sorted({w for g in grid.values() if "persist" in g
                      for w in [persist_warps(g["persist"])] if w is not None})
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (stage, _) in zip(panels, STAGES):
        for i, (scene, g) in enumerate(grid.items()):
            runs = [(r.get("options", {}), s[stage]) for _, r, s in g["queue"] if stage in s]
            if not runs:
                continue
            # The defaults' time (groups of 256, no pad), else the most warps'.
            default = [v for o, v in runs if (o.get("queue-group") or 256) == 256
                       and not o.get("queue-local-pad")]
            base = (default or [max(runs, key=lambda x: x[1][1])[1]])[0][0]
            color, marker = colors[i % len(colors)], MARKERS[i % len(MARKERS)]
            padded = sorted((w, ms / base) for o, (ms, w) in runs if o.get("queue-local-pad"))
            plain = [(w, ms / base) for o, (ms, w) in runs if not o.get("queue-local-pad")]
            line, = ax.plot([w for w, _ in padded], [y for _, y in padded], color=color,
                            marker=marker, linewidth=1, markersize=4)
            ax.plot([w for w, _ in plain], [y for _, y in plain], linestyle="none", marker=marker,
                    markersize=5, markerfacecolor="none", color=color)
            if stage == STAGES[0][0]:
                handles.append(line)
                labels.append(short(scene))
        for w in persist:
            ax.axvline(w, color="black", linestyle=":", linewidth=0.8)
        ax.set_title(stage, fontsize=9)
        ax.set_xlabel("resident warps a multiprocessor", fontsize=8)
        ax.set_ylabel("time / time at the defaults", fontsize=8)
        ax.set_xlim(0, MAX_WARPS)
        ax.grid(alpha=0.3)
    legend_row(legend_ax, handles, labels)
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rows", help="rows.jsonl of bench/sweeps/queue-occupancy")
    ap.add_argument("--out", default=None, help="folder for occupancy.md and occupancy.png "
                    "[beside the rows]")
    a = ap.parse_args(argv)
    meta, rows = load(a.rows)
    grid = gather(rows)
    if not grid:
        sys.exit(f"{a.rows}: no queue rows with kernel times and registers (kernel_ms, "
                 "kernel_resources: an NVIDIA device's)")
    out = a.out or os.path.dirname(os.path.abspath(a.rows))
    os.makedirs(out, exist_ok=True)
    table(meta, grid, os.path.join(out, "occupancy.md"))
    try:
        chart(meta, grid, os.path.join(out, "occupancy.png"))
    except ImportError:
        print("charts_occupancy: no matplotlib (scripts/setup installs it): table only",
              file=sys.stderr)
    print(os.path.join(out, "occupancy.md"))

