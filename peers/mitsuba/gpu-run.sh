#!/usr/bin/env bash
# peers/mitsuba/gpu-run.sh — the Mitsuba 3 / Dr.Jit peer's GPU run (issue 53), one command on the
# device machine, from the repository root, with the repacked wheels carried in .whl/
# (peers/mitsuba/repack-wheels.sh; the host has python3.12 and numpy, no internet):
#
#   1. installs mitsuba 3.9.1 and drjit 1.5.0 from .whl/ into /tmp/site;
#   2. writes the map walls the scene list names (scripts/make-map.py --sweep, standard library);
#   3. times the peer (timing.py) on each scene in Dr.Jit's symbolic (megakernel) and evaluated
#      (wavefront) modes, each scene under `timeout`, and stops starting scenes past a budget;
#   4. with RTLAB_BIN (an rtlab binary that writes EXR), checks the peer's cuda_ad_rgb images
#      against rtlab's cpu reference at a small size (compare.py); without it, renders those
#      images as EXR (peer-check.tar.gz) for `compare.py SCENES --peer-images DIR` at home;
#   5. leaves in $OUT at most 8 files: peer-rows.jsonl (timing rows), peer-compare.jsonl or
#      peer-check.jsonl and peer-check.tar.gz, peer-images.tar.gz (the last frame of every
#      scene and mode, PNG), log.txt, env.txt.
#
# Usage (the device command; carry .whl):
#   bash peers/mitsuba/gpu-run.sh                 # the scene set of bench/sweeps/peer-mitsuba
#   bash peers/mitsuba/gpu-run.sh scenes/cornell.json scenes/divergence.json   # named scenes (walls
#                                                 # must exist: scripts/make-map.py)
# Environment: PEER_VARIANT (cuda_ad_rgb; llvm_ad_rgb times the host's CPU, which needs libLLVM
# >= 15), PEER_SIZE (1920x1080), PEER_BOUNCES (4), PEER_MODES (symbolic,evaluated),
# PEER_REPEATS (5), PEER_WARMUP (2), PEER_STEP_TIMEOUT (seconds a scene may take, 150),
# PEER_BUDGET (seconds after which no new scene starts, 420), PEER_SPHERES (ellipsoids),
# PEER_STACK (local: the ray-tree stack in Dr.Jit local memory; registers: in loop variables),
# PEER_COMPARE_SIZE (480x270), RTLAB_BIN (rtlab, for the image check; skipped without it),
# RTLAB_COMMIT (the commit the rows name, where the copy has no .git),
# PEER_SHARD (i/N: every N-th scene from the i-th, to split the set over several calls),
# PEER_SWEEP (the sweep file whose first scenes line is the set; bench/sweeps/peer-mitsuba-cpu is
# the CPU's, at 480x270).
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
OUT=${OUT:-$ROOT/out-peer}
mkdir -p "$OUT"
exec > >(tee -a "$OUT/log.txt") 2>&1
VARIANT=${PEER_VARIANT:-cuda_ad_rgb}
SIZE=${PEER_SIZE:-1920x1080}
BOUNCES=${PEER_BOUNCES:-4}
MODES=${PEER_MODES:-symbolic,evaluated}
REPEATS=${PEER_REPEATS:-5}
WARMUP=${PEER_WARMUP:-2}
STEP=${PEER_STEP_TIMEOUT:-150}
BUDGET=${PEER_BUDGET:-420}
SPHERES=${PEER_SPHERES:-ellipsoids}
STACK=${PEER_STACK:-local}
CSIZE=${PEER_COMPARE_SIZE:-480x270}
SWEEP=${PEER_SWEEP:-bench/sweeps/peer-mitsuba}
start=$SECONDS

echo "== install (.whl: $(ls .whl/*.whl 2>/dev/null | xargs -n1 basename | tr '\n' ' '))"
ls .whl/*.whl >/dev/null 2>&1 || { echo "gpu-run.sh: no wheels in .whl/ (carry .whl; peers/mitsuba/repack-wheels.sh)"; exit 1; }
timeout 300 python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl || { echo "gpu-run.sh: pip install failed"; exit 1; }
export PYTHONPATH=/tmp/site${PYTHONPATH:+:$PYTHONPATH}
# The commit the rows name: $RTLAB_COMMIT if the caller gives it (a copy without .git), else git's.
if [ -z "${RTLAB_COMMIT:-}" ]; then
    RTLAB_COMMIT=$(git rev-parse --short=12 HEAD 2>/dev/null || echo unknown)
    [ -n "$(git status --porcelain -- peers 2>/dev/null)" ] && RTLAB_COMMIT+=-dirty
fi
export RTLAB_COMMIT
{
    echo "commit: ${RTLAB_COMMIT:-$(git rev-parse HEAD 2>/dev/null || echo unknown)}"
    python3 --version
    python3 -c "import numpy, drjit, mitsuba; print('numpy', numpy.__version__, 'drjit', drjit.__version__, 'mitsuba', mitsuba.__version__)"
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1
    nproc
} > "$OUT/env.txt" 2>&1
cat "$OUT/env.txt"

if [ $# -gt 0 ]; then
    all=("$@")
else
    echo "== map walls of $SWEEP"
    timeout 300 python3 scripts/make-map.py --sweep "$SWEEP" --out scenes/map >/dev/null \
        || echo "gpu-run.sh: make-map.py failed; walls missing below"
    names=$(sed -n 's/#.*//; s/^[[:space:]]*scenes[[:space:]]*=//p' "$SWEEP" | head -1)
    all=()
    for n in $names; do all+=("scenes/$n.json"); done
fi
# PEER_SHARD=i/N: every N-th scene from the i-th (1-based), to split the set over calls.
SHARD=${PEER_SHARD:-1/1}
si=${SHARD%/*}; sn=${SHARD#*/}
scenes=()
for k in "${!all[@]}"; do
    [ $((k % sn)) -eq $((si - 1)) ] && scenes+=("${all[$k]}")
done
echo "== ${#scenes[@]} scenes, $VARIANT, $SIZE, B = $BOUNCES, modes $MODES, $WARMUP warm-up + $REPEATS repeats"

for s in "${scenes[@]}"; do
    if [ $((SECONDS - start)) -gt "$BUDGET" ]; then
        echo "gpu-run.sh: budget of ${BUDGET}s spent; not started: $s"
        echo "{\"scene\": \"$(basename "$s" .json)\", \"skipped\": \"budget\"}" >> "$OUT/peer-rows.jsonl"
        continue
    fi
    [ -f "$s" ] || { echo "gpu-run.sh: $s: no such scene"; continue; }
    echo "== $s ($((SECONDS - start))s)"
    timeout -k 10 "$STEP" python3 peers/mitsuba/timing.py "$s" --variant "$VARIANT" \
        --size "$SIZE" --bounces "$BOUNCES" --modes "$MODES" --repeats "$REPEATS" \
        --warmup "$WARMUP" --spheres "$SPHERES" --stack "$STACK" --out "$OUT/peer-rows.jsonl" \
        --images "$OUT/images" >/dev/null
    rc=$?
    [ $rc -eq 0 ] || { echo "gpu-run.sh: $s: exit status $rc (124: past ${STEP}s)";
        echo "{\"scene\": \"$(basename "$s" .json)\", \"error\": \"exit status $rc\"}" >> "$OUT/peer-rows.jsonl"; }
done
[ -f "$OUT/peer-rows.jsonl" ] && python3 - "$OUT/peer-rows.jsonl" <<'EOF'
import json, sys
for line in open(sys.argv[1]):
    r = json.loads(line)
    print(f"{r.get('scene', '?'):26} {r.get('mode', '-'):10} median {r.get('median_ms', '-'):>10} ms"
          f"  compile {r.get('compile_ms', '-'):>9} ms  launches {r.get('launches', '-'):>5}"
          f"  {r.get('error', r.get('not_converted', r.get('skipped', '')))}")
EOF

cmp=()
for s in scenes/cornell.json scenes/spheres.json scenes/shadows.json scenes/mesh.json \
         scenes/divergence.json scenes/envmap.json scenes/map/map-s16-x50-o8-m16.json \
         scenes/map/map-s64-x100-o8-m16.json scenes/map/map-s16-t80-x50-o8-m16.json; do
    [ -f "$s" ] && cmp+=("$s")
done
if [ -n "${RTLAB_BIN:-}" ] && [ -x "${RTLAB_BIN:-}" ]; then
    echo "== images against rtlab's cpu reference at $CSIZE ($((SECONDS - start))s)"
    timeout -k 10 240 python3 peers/mitsuba/compare.py "${cmp[@]}" --variant "$VARIANT" \
        --size "$CSIZE" --bounces "$BOUNCES" --modes "$MODES" --rtlab "$RTLAB_BIN" \
        --out /tmp/peer-compare --json "$OUT/peer-compare.jsonl" >/dev/null \
        || echo "gpu-run.sh: compare.py: exit status $?"
    [ -f "$OUT/peer-compare.jsonl" ] && python3 - "$OUT/peer-compare.jsonl" <<'EOF'
import json, sys
for line in open(sys.argv[1]):
    r = json.loads(line)
    if "within_2" in r:
        print(f"{r['scene']:26} {r['mode']:10} within 2/255 {100 * r['within_2']:7.3f}%  mean "
              f"{r['mean']:.3f}  max {r['max']:.1f}  rays {r['rays']}")
    else:
        print(f"{r.get('scene', '?'):26} {r.get('not_converted', r.get('error', ''))}")
EOF
else
    # No rtlab here: the peer's images of the check scenes as EXR, compared at home with
    # compare.py SCENES --size $CSIZE --peer-images DIR (the folder in peer-check.tar.gz).
    echo "== no RTLAB_BIN: the check scenes' images at $CSIZE for compare.py --peer-images"
    timeout -k 10 240 python3 peers/mitsuba/compare.py "${cmp[@]}" --variant "$VARIANT" \
        --size "$CSIZE" --bounces "$BOUNCES" --modes "$MODES" --no-reference \
        --out "$OUT/check" --json "$OUT/peer-check.jsonl" >/dev/null \
        || echo "gpu-run.sh: compare.py --no-reference: exit status $?"
    [ -d "$OUT/check" ] && tar -C "$OUT" -czf "$OUT/peer-check.tar.gz" check && rm -rf "$OUT/check"
fi

if [ -d "$OUT/images" ]; then
    tar -C "$OUT" -czf "$OUT/peer-images.tar.gz" images && rm -rf "$OUT/images"
fi
echo "== done in $((SECONDS - start))s; $OUT: $(ls "$OUT" | tr '\n' ' ')"
