#!/usr/bin/env bash
# Runs a sweep (bench/sweeps/full by default) on a GPU host that has no OpenImageIO (any Linux
# machine with an OpenCL GPU driver: rtlab-bench and its libraries travel with it), and turns
# what comes back into results/<device-slug>/ here.
#
#   scripts/gpu-sweep.sh prepare [SWEEP...] [--resume DIR]...
#       Builds rtlab and rtlab-bench from a clean clone of HEAD (so every result names an exact
#       commit) in build-gpu/, and fills carry/gpu-sweep/ (git-ignored) with rtlab-bench, the
#       libraries it needs beside it (libbenchmark.so.1debian, libtinyobjloader, libassimp with
#       libdraco and libminizip; not libOpenCL.so.1, the GPU host's own ICD loader is used, nor
#       libz, which every host has and its driver libraries load too),
#       the scenes with .pfm cubemap faces, the sweep file, run.sh and smoke.sh (scripts/gpu-smoke,
#       the check to pass before any GPU result is called done) and batch.sh (scripts/gpu-batch:
#       the smoke check and several sweeps in one session, one file back). Several SWEEPs: all
#       travel, run.sh runs the first (RTLAB_SWEEP=NAME another). --resume DIR (a folder
#       copied back from an earlier run) makes the new run skip the cells that one measured.
#       Generated scenes are too large to carry (the map's walls, the stress scenes): the
#       generators travel instead (scripts/make-map.py, make-stress.py; Python's standard
#       library only) and run.sh writes the scenes the sweep names on the host, before the
#       sweep. The real models a sweep names (real/...) are copied in by scripts/copy-models.sh.
#   scripts/gpu-sweep.sh command
#       Prints the steps below.
#   scripts/gpu-sweep.sh import DIR [DIR...]
#       Unpacks each copied-back folder (images.tar.xz or its parts) and runs
#       `rtlab sweep SWEEP --import ...` from the measured commit: accuracy against the converged
#       CPU reference through OpenImageIO, CSV, JSON, the five charts and README.md into
#       results/<device-slug>/, with the Google Benchmark JSON and the device log beside them
#       (the phase and occupancy sweeps' own charts in SWEEP-phases/ and SWEEP-warps/).
#       Several folders: runs continued with --resume, or the shards of one sweep, merged in the
#       sweep's cell order. results/<device-slug>/ is the device's published set: an experiment
#       imports elsewhere (RTLAB_RESULTS_DIR=/tmp/exp) and is filed with
#       `python3 tools/rtlab_report experiment results NAME ...` (results/README.md says how).
#
# On the GPU host (from the folder that holds carry/gpu-sweep/):
#   OUT=/path/to/out bash carry/gpu-sweep/smoke.sh     (the smoke check: every cell must PASS)
#   OUT=/path/to/out bash carry/gpu-sweep/run.sh
# The sweep stops itself after RTLAB_GPU_TIME_LIMIT seconds (480 by default; a session or job
# with a time limit sets it below that) and `prepare --resume` continues it. RTLAB_GPU_DEVICES=all
# (or 0,1) spreads the cells over the host's GPUs; RTLAB_SHARD=i/N runs share i of N, one per
# machine or array task (bench/sweeps/README.md). What it writes to $OUT (at most 8 files):
# sweep.json, rows.jsonl, log.txt, gbench.json and images.tar.xz (or images.tar.xz.part-aa, -ab,
# ... past 15 MiB). Copy that folder back here and import it.
set -euo pipefail
cd "$(dirname "$0")/.."
# The report package's commands (charts, readme, ...), through Debian's python3-matplotlib.
report() { /usr/bin/python3 tools/rtlab_report "$@"; }
ROOT=$PWD
BUILD=$ROOT/build-gpu
CARRY=carry/gpu-sweep
RESULTS=$(realpath -m "${RTLAB_RESULTS_DIR:-results}")  # import writes $RESULTS/<device-slug>/

die() { echo "gpu-sweep: $*" >&2; exit 1; }

build_clean() {
    local sha
    sha=$(git rev-parse HEAD)
    [ -d "$BUILD/src/.git" ] || git clone -q --no-hardlinks "$ROOT" "$BUILD/src"
    git -C "$BUILD/src" fetch -q "$ROOT" "$sha"
    git -C "$BUILD/src" checkout -q --detach "$sha"
    if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
        echo "gpu-sweep: note: the working tree has uncommitted changes; the GPU build is HEAD" \
             "($(git rev-parse --short=12 HEAD)) alone" >&2
    fi
    cmake -S "$BUILD/src" -B "$BUILD/build" -DCMAKE_BUILD_TYPE=Release -DRTLAB_BUILD_TESTS=OFF \
          -DRTLAB_BUILD_VIEWER=OFF >/dev/null
    cmake --build "$BUILD/build" -j"$(nproc)" --target rtlab rtlab-bench
}

# The scene names of a sweep file's scenes lines, one a line.
sweep_scenes() { sed -n 's/#.*//; s/^[[:space:]]*scenes[[:space:]]*=//p' "$1" | tr ' ,' '\n\n'; }

# The file an executable's dependency `name` resolves to here.
lib_path() { ldd "$1" | awk -v n="$2" '$1 == n { print $3 }'; }

prepare() {
    local sweeps=() resumes=() i=1 path missing sweep
    while [ $# -gt 0 ]; do
        case $1 in
            --resume) [ $# -ge 2 ] || die "--resume needs a folder"; resumes+=("$2"); shift 2 ;;
            -*) die "unknown option $1" ;;
            *) sweeps+=("$1"); shift ;;
        esac
    done
    [ ${#sweeps[@]} -gt 0 ] || sweeps=(full)
    for sweep in "${sweeps[@]}"; do
        [ -f "bench/sweeps/$sweep" ] || die "no sweep bench/sweeps/$sweep"
    done
    build_clean
    rm -rf "$CARRY"
    mkdir -p "$CARRY/bin" "$CARRY/sweeps" "$CARRY/resume"
    cp "$BUILD/build/bin/rtlab-bench" "$CARRY/bin/"
    for lib in libbenchmark.so.1debian libtinyobjloader.so.2rc10 libassimp.so.5 libdraco.so.7 \
               libminizip.so.1; do
        path=$(lib_path "$BUILD/build/bin/rtlab-bench" "$lib")
        [ -z "$path" ] || cp -L "$path" "$CARRY/bin/$lib"
    done
    # As run.sh loads it: the carried libraries' own dependencies (libassimp's) are found there too.
    missing=$(LD_LIBRARY_PATH=$ROOT/$CARRY/bin ldd "$CARRY/bin/rtlab-bench" |
              grep -v -e libc.so -e libm.so -e libstdc++ -e libgcc_s -e ld-linux -e vdso \
                  -e libOpenCL.so.1 -e libz.so.1 -e "=> $ROOT/$CARRY/bin/" || true)
    [ -z "$missing" ] || echo "gpu-sweep: rtlab-bench also needs (not carried): $missing" >&2
    (cd "$BUILD/src" && "$BUILD/build/bin/rtlab" sweep --export-scenes "$ROOT/$CARRY/scenes") >/dev/null
    for sweep in "${sweeps[@]}"; do cp "$BUILD/src/bench/sweeps/$sweep" "$CARRY/sweeps/"; done
    mkdir -p "$CARRY/scripts"
    cp "$BUILD/src/scripts/make-map.py" "$BUILD/src/scripts/make-stress.py" "$CARRY/scripts/"
    # The shared models sit beside this checkout, not the clean clone: copy from here.
    if cat "$CARRY"/sweeps/* | sweep_scenes /dev/stdin | grep -q '^real/'; then
        "$ROOT/scripts/copy-models.sh" "$ROOT/$CARRY/scenes/real" >/dev/null
    fi
    echo "${sweeps[0]}" >"$CARRY/SWEEP"
    for dir in "${resumes[@]+"${resumes[@]}"}"; do
        [ -f "$dir/rows.jsonl" ] || die "--resume $dir: no rows.jsonl there"
        cp "$dir/rows.jsonl" "$CARRY/resume/rows-$i.jsonl"
        i=$((i + 1))
    done
    cp "$BUILD/src/scripts/gpu-sweep-run.sh" "$CARRY/run.sh"
    cp "$BUILD/src/scripts/gpu-smoke" "$CARRY/smoke.sh"
    cp "$BUILD/src/scripts/gpu-batch" "$CARRY/batch.sh"
    cp "$BUILD/src/scripts/gpu-env.sh" "$CARRY/gpu-env.sh"
    echo "gpu-sweep: $CARRY ready ($(du -sh "$CARRY" | cut -f1)), commit" \
         "$(git -C "$BUILD/src" rev-parse --short=12 HEAD), sweeps ${sweeps[*]}"
    if [ "$(du -sm "$CARRY" | cut -f1)" -gt 64 ]; then
        echo "gpu-sweep: note: $CARRY is over 64 MiB, more than some GPU sessions carry" >&2
    fi
    command_help
}

command_help() {
    cat <<'TEXT'
1. Copy carry/gpu-sweep/ to the GPU host, e.g.
     rsync -a carry/gpu-sweep HOST:rtlab/carry/
2. Run it there (the sweep stops itself after RTLAB_GPU_TIME_LIMIT seconds, 480 by default):
     ssh HOST 'cd rtlab && OUT=$PWD/out bash carry/gpu-sweep/run.sh'
   Several GPUs on the host: RTLAB_GPU_DEVICES=all. Several hosts or an array job: RTLAB_SHARD=i/N
   in task i (e.g. RTLAB_SHARD=$SLURM_ARRAY_TASK_ID/N), each task with its own OUT.
3. Copy the output folder back and import it (every shard's folder at once):
     rsync -a HOST:rtlab/out/ /tmp/gpu-out/ && scripts/gpu-sweep.sh import /tmp/gpu-out
If log.txt says the time limit stopped the sweep, continue it, then import both:
  scripts/gpu-sweep.sh prepare full --resume /tmp/gpu-out     (copy and run again, into out-2)
  scripts/gpu-sweep.sh import /tmp/gpu-out /tmp/gpu-out-2
TEXT
}

json_field() {
    /usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])' "$1" "$2"
}

import() {
    [ $# -ge 1 ] || die "import needs the copied-back folder(s)"
    [ -x "$BUILD/build/bin/rtlab" ] || die "run prepare first (it builds $BUILD/build/bin/rtlab)"
    local staged=() n=0 stage sweep slug
    for dir in "$@"; do
        [ -f "$dir/sweep.json" ] || die "$dir: no sweep.json (did the run fail? see $dir/log.txt)"
        n=$((n + 1))
        stage=$BUILD/import-$n
        rm -rf "$stage" && mkdir -p "$stage"
        cp "$dir/sweep.json" "$dir/rows.jsonl" "$stage/"
        if ls "$dir"/images.tar.xz* >/dev/null 2>&1; then
            cat "$dir"/images.tar.xz* >"$stage/images.tar.c"
            tar -C "$stage" -xf "$stage/images.tar.c"  # xz or gzip: tar tells them apart
            rm "$stage/images.tar.c"
        fi
        staged+=("$stage")
    done
    sweep=$(json_field "$1/sweep.json" sweep)
    slug=$(json_field "$1/sweep.json" device_slug)
    local dest=$RESULTS/$slug
    mkdir -p "$dest"
    # Scenes and the reference renderer come from the commit that was measured.
    (cd "$BUILD/src" && "$BUILD/build/bin/rtlab" sweep "bench/sweeps/$sweep" \
        --import "${staged[@]}" --out "$dest" --no-charts --force)
    n=0
    for dir in "$@"; do
        n=$((n + 1))
        [ ! -f "$dir/gbench.json" ] || cp "$dir/gbench.json" "$dest/$sweep-google-benchmark-$n.json"
        [ ! -f "$dir/log.txt" ] || cp "$dir/log.txt" "$dest/$sweep-device-log-$n.txt"
    done
    report charts "$dest/$sweep.json"
    # The persistent megakernel's sweeps have one frame size and many schedules: their own chart.
    case $sweep in persist*) report persist-charts "$dest/$sweep.json" ;; esac
    # Diagnostic sweeps have a chart of their own, in a folder of their own.
    case $sweep in
        persist-phase | persist-bounce-phase)
            report phase-charts "$dest/$sweep.json" --out "$dest/$sweep-phases" ;;
        queue-occupancy)
            report occupancy-charts "$dest/$sweep.json" --out "$dest/$sweep-warps" ;;
    esac
    report readme "$dest/$sweep.json"
    echo "gpu-sweep: $dest/ ready"
}

case ${1:-} in
    prepare) shift; prepare "$@" ;;
    command) command_help ;;
    import) shift; import "$@" ;;
    *) sed -n '2,/^set -euo/p' "$0" | sed '$d'; exit 2 ;;
esac
