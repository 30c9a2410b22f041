#!/usr/bin/env bash
# Runs on the GPU host as carry/gpu-sweep/run.sh (made by `scripts/gpu-sweep.sh prepare` beside
# rtlab-bench, its libraries, the scenes and the sweep; copied there with them). Writes the
# generated scenes the sweep names (map walls, stress scenes) with the carried generators, finds
# NVIDIA's OpenCL, runs the sweep under a time limit, packs the kept frames, and runs a few
# Google Benchmark cells. It writes to $OUT (default ./out), which goes back for
# `scripts/gpu-sweep.sh import`; log.txt holds its output. RTLAB_GPU_DEVICES=all (or a list)
# runs the cells on several GPUs at once; RTLAB_SHARD=i/N runs one share of the sweep (one
# machine or array task of N). RTLAB_GPU_PREBUILD=N first runs the sweep's cells once, untimed,
# in N processes at once, so that the programs it needs are built on N cores and the timed run
# finds them in the program cache (a fresh host builds each one for seconds, a tree-layout
# megakernel once per bounce limit for 13-33 s on NVIDIA).
set -uo pipefail
C=$(cd "$(dirname "$0")" && pwd)
OUT=${OUT:-$PWD/out}
mkdir -p "$OUT"
SWEEP=${RTLAB_SWEEP:-$(cat "$C/SWEEP")}  # RTLAB_SWEEP: another carried sweep (batch.sh)
LIMIT=${RTLAB_GPU_TIME_LIMIT:-480}
DEVICE=${RTLAB_GPU_DEVICE:-gpu}  # "cpu" rehearses the whole run on PoCL
DEVICES=${RTLAB_GPU_DEVICES:-}  # "all" or "0,1": the sweep on several devices at once
SHARD=${RTLAB_SHARD:-}          # "i/N": this machine's share of the sweep
PREBUILD=${RTLAB_GPU_PREBUILD:-0}  # processes that build the programs before the timed run
[[ $PREBUILD =~ ^[0-9]+$ ]] || {
    echo "run.sh: RTLAB_GPU_PREBUILD '$PREBUILD': must be a whole number of processes" >&2
    exit 2
}
GBENCH_S=${RTLAB_GPU_GBENCH_S:-60}  # time for the Google Benchmark cells at the end; 0 skips them
export LD_LIBRARY_PATH=$C/bin${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export RTLAB_CACHE_DIR=/tmp/rtlab-cache

source "$C/gpu-env.sh"  # find_nvidia_opencl

pack_frames() {
    local w=$1
    [ -d "$w/images" ] && [ -n "$(ls -A "$w/images")" ] || return 0
    if command -v xz >/dev/null; then
        tar -C "$w" -cf - images | xz -T0 -6 >"$OUT/images.tar.xz"
    else
        tar -C "$w" -czf "$OUT/images.tar.xz" images  # the import step reads either
    fi
    if [ "$(stat -c %s "$OUT/images.tar.xz")" -gt $((15 * 1024 * 1024)) ]; then
        split -b 15M "$OUT/images.tar.xz" "$OUT/images.tar.xz.part-" && rm "$OUT/images.tar.xz"
    fi
}

# The generated scenes the sweep names, written into the carried scene folder: too large to
# carry, seconds to make (Python's standard library only).
make_scenes() {
    local sweep=$C/sweeps/$SWEEP names want=() only
    names=$(sed -n 's/#.*//; s/^[[:space:]]*scenes[[:space:]]*=//p' "$sweep" | tr ' ,' '\n\n')
    grep -q '^map/' <<<"$names" && want+=(map)
    grep -qx 'stress/many-spheres' <<<"$names" && want+=(spheres)
    grep -qx 'stress/big-mesh' <<<"$names" && want+=(mesh)
    [ ${#want[@]} -gt 0 ] || return 0
    command -v python3 >/dev/null || { echo "no python3 to write the generated scenes"; return 1; }
    echo "== generated scenes (${want[*]})"
    local start=$SECONDS
    for only in "${want[@]}"; do
        case $only in
            map) python3 "$C/scripts/make-map.py" --sweep "$sweep" --out "$C/scenes/map" | wc -l |
                     sed 's/$/ map scenes/' ;;
            *) python3 "$C/scripts/make-stress.py" --out "$C/scenes/stress" --only "$only" ;;
        esac || return 1
    done
    echo "generated in $((SECONDS - start)) s ($(du -sh "$C/scenes" | cut -f1) of scenes)"
}

# The cells still to measure, once each (one frame, no warm-up), split over $PREBUILD processes:
# nothing is kept but the programs they leave in the cache. Bounded by a third of the time
# limit, which its time counts against; a process cut short only leaves the timed run more to
# build.
prebuild() {
    local resume=$1 i start=$SECONDS once=/tmp/rtlab-prebuild.sweep
    sed -E 's/^(repeats|warmup)[[:space:]]*=.*/\1 = 1/; s/^warmup = 1/warmup = 0/' \
        "$C/sweeps/$SWEEP" >"$once"
    echo "== building programs in $PREBUILD processes"
    for ((i = 0; i < PREBUILD; i++)); do
        rm -rf "/tmp/rtlab-prebuild-$i"
        timeout $((LIMIT / 3 + 15)) "$C/bin/rtlab-bench" --sweep "$once" \
            --out "/tmp/rtlab-prebuild-$i" "${where[@]}" --scene-dir "$C/scenes" \
            --time-limit $((LIMIT / 3)) --shard "$i/$PREBUILD" ${resume:+--resume "$resume"} \
            >/dev/null 2>&1 &
    done
    wait
    echo "programs built in $((SECONDS - start)) s ($(ls /tmp/rtlab-cache 2>/dev/null | wc -l) in the cache)"
}

main() {
    echo "== machine"
    uname -a
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1 | head -3
    make_scenes || return 4
    find_nvidia_opencl
    echo "== devices"
    "$C/bin/rtlab-bench" --list-devices | tee /tmp/rtlab-devices.txt
    if [ "$DEVICE" = gpu ] && ! grep -q '\[GPU\]' /tmp/rtlab-devices.txt; then
        echo "no OpenCL GPU: stopping"
        return 3
    fi

    local resume status w=/tmp/rtlab-sweep
    resume=$(ls "$C"/resume/*.jsonl 2>/dev/null | paste -sd, -)
    local where=(--device "$DEVICE")
    [ -z "$DEVICES" ] || where=(--devices "$DEVICES")
    if [ "$PREBUILD" -gt 0 ]; then
        local before=$SECONDS
        prebuild "$resume"
        LIMIT=$((LIMIT - (SECONDS - before)))  # the whole run keeps to RTLAB_GPU_TIME_LIMIT
        [ "$LIMIT" -gt 10 ] || LIMIT=10
    fi
    echo "== sweep $SWEEP${SHARD:+, shard $SHARD} (stops itself after ${LIMIT} s${resume:+; skips what $resume measured})"
    rm -rf "$w"
    # The hard stop still keeps the rows measured so far: rows.jsonl is written cell by cell.
    timeout $((LIMIT + 30)) "$C/bin/rtlab-bench" --sweep "$C/sweeps/$SWEEP" --out "$w" \
        "${where[@]}" --scene-dir "$C/scenes" --time-limit "$LIMIT" ${resume:+--resume "$resume"} \
        ${SHARD:+--shard "$SHARD"}
    status=$?
    cp "$w/sweep.json" "$w/rows.jsonl" "$OUT/"
    echo "== packing frames"
    pack_frames "$w"

    if [ "$GBENCH_S" -gt 0 ]; then
        echo "== Google Benchmark: headline cells (programs cached by the sweep)"
        timeout "$GBENCH_S" "$C/bin/rtlab-bench" --device "$DEVICE" --scene-dir "$C/scenes" \
            --scenes=spheres,cornell,mesh --sizes=1920x1080 --bounces=4 --repeats=5 \
            --benchmark_min_time=0.2 --benchmark_out="$OUT/gbench.json" \
            --benchmark_out_format=json >/dev/null || echo "(Google Benchmark: status $?)"
    fi
    ls -la "$OUT"
    echo "== done (sweep status $status)"
    return "$status"
}

main 2>&1 | tee "$OUT/log.txt"
exit "${PIPESTATUS[0]}"
