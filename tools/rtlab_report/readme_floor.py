"""Each frame against its memory floor, for the generated result READMEs.

The floor of a frame is the global-memory traffic its pipeline's design cannot avoid, divided by
the copy bandwidth rtlab-roofline measured on the same device (roofline.json beside the sweep):
if the frame did nothing but move those bytes at that rate, it would take `floor ms`. Bytes are
counted from what every row carries (size, AA, tree nodes N, the global tree, ray counts or the
queue's per-bounce lengths), never from timings, and as the kernels load and store them: a
lower bound, since caches, 32-byte sectors and scene reads only add to it.

  every pipeline   the finished image, 12 B (RGB float) per pixel, written once
  wave (a global   per AA sample and pixel: Wavefront_Reset clears the pixel's traced flags
    ray tree)      (N bits in 32-bit words: tree_pixel_bytes - 48 N; rows from before the bit
                   mask kept one flag byte inside each 48-byte node, so N bytes), and each traced
                   node (48 B, sizeof(Node) in core/types.h) is written by Wavefront_Trace and read
                   by Wavefront_Image (the counted primary, reflection and refraction rays;
                   without counts only the primary ray, one per pixel and sample). Slots no ray
                   reached need not be read: the design's floor, whatever an implementation does
  queue (a pool    per ray extended (the sum of extras.queue_lengths: every extended ray lands
    of live rays)  in one class queue): its ray record (44 B) written and read once, and its
                   hit record (48 B) written by extend and read by shade
  mega             nothing else: its rays and trees live in private memory

Standard library only.
"""
import json
import os

from .readme_format import ms, size_label, table
from .sweep_rows import LEGACY_NODE_BYTES, setting

IMAGE_BYTES_PER_PIXEL = 12  # RGB float
# Rows record their pipeline's record sizes (extras: node_bytes, ray_record_bytes,
# hit_record_bytes); rows from before they did had these: a 48-byte node, and the queue's ray
# record of origin, direction, weight, pixel and meta.
LEGACY_RAY_BYTES = 44

FLOOR_TEXT = (
    "Floor: the bytes a frame's design must move through global memory, divided by the copy "
    "bandwidth rtlab-roofline measured on this device ({gbs:.0f} GB/s, read + write, "
    "[`roofline.json`](roofline.json)). Counted per frame: the image (12 B a pixel) for every "
    "pipeline; for the report's wavefront, per pixel and AA sample, the traced flags the reset "
    "kernel clears (N bits), and each traced node (48 B) written by the trace kernel and read by "
    "the image kernel (the counted rays, else one primary ray): slots no ray reached need not be "
    "touched; for the queue wavefront, per "
    "ray extended (the sum of its per-bounce queue lengths), the ray record (44 B) and hit record "
    "(48 B), each written once and read once. The megakernel keeps its rays in private memory: "
    "its floor is the image alone, so its frame / floor says how far from memory-bound it is. "
    "A lower bound: caches, 32-byte sectors and scene reads only add to it "
    "(tools/rtlab_report/readme_floor.py).")


def read_roofline(folder):
    path = os.path.join(folder, "roofline.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        roof = json.load(f)
    return roof if roof.get("copy_gb_per_s", 0) > 0 else None


def floor_bytes(r):
    """Bytes the frame of row r must move (see the module text), or None for a row that did not
    run."""
    if r.get("status") != "ok":
        return None
    pixels = r["width"] * r["height"]
    samples = pixels * r.get("aa", 1) ** 2
    total = pixels * IMAGE_BYTES_PER_PIXEL
    extras = r.get("extras") or {}
    if r.get("tree_bytes", 0) > 0:
        nodes = r["tree_nodes"]
        node_bytes = extras.get("node_bytes", LEGACY_NODE_BYTES)
        rays = r.get("rays") or {}
        traced = sum(rays.get(t, 0) for t in ("primary", "reflection", "refraction")) or samples
        pixel = extras.get("tree_pixel_bytes")
        flags = pixel - nodes * node_bytes if pixel else nodes  # bit mask, or a byte a node
        total += samples * flags + traced * 2 * node_bytes
    lengths = extras.get("queue_lengths")
    if lengths:
        extended = sum(sum(depth) for depth in lengths)
        total += extended * 2 * (extras.get("ray_record_bytes", LEGACY_RAY_BYTES) +
                                 extras.get("hit_record_bytes", LEGACY_NODE_BYTES))
    return total


def floor_ms(r, roof):
    b = floor_bytes(r)
    return None if b is None else b / (roof["copy_gb_per_s"] * 1e9) * 1e3


def floor_section(rows, series_of, here):
    """The README section: per setting, each series' floor and its frame over it; [] without a
    roofline.json beside the README."""
    roof = read_roofline(here)
    if roof is None:
        return []
    series = series_of(rows)
    by, order = {}, []
    for r in rows:
        if floor_bytes(r) is None:
            continue
        k = setting(r)
        if k not in by:
            order.append(k)
        by.setdefault(k, {})[series.key(r)] = r
    keys = [s for s in series.keys if any(s in by[k] for k in order)]
    body = []
    for k in order:
        cells = by[k]
        r = next(iter(cells.values()))
        line = [r["scene"], size_label(r), r["bounces"], r["aa"]]
        for s in keys:
            c = cells.get(s)
            f = floor_ms(c, roof) if c else None
            line += ["—", "—"] if f is None else [ms(f), f"{c['device_ms'] / f:.1f}"]
        body.append(line)
    head = ["Scene", "Resolution", "B", "AA"]
    for s in keys:
        head += [f"{series.label(s)} floor ms", f"{series.label(s)} frame / floor"]
    return ["## Each frame against its floor", "",
            FLOOR_TEXT.format(gbs=roof["copy_gb_per_s"]), "", table(head, body), ""]
