#!/usr/bin/env bash
# Copies the real models of bench/sweeps/models, which nobody on this project made, into
# scenes/real/ (git-ignored; scenes/README.md, "Real models"):
#   2CylinderEngine.glb  from Debian's assimp-testmodels (scripts/setup installs it): a Khronos
#                        glTF 2.0 sample model, 34 materials, its own camera
#   bunny.obj            the Stanford bunny, from the shared model folder beside the checkout
#                        (../shared/models, or $RTLAB_SHARED_MODELS)
# The sweep reads them as bare models, so each keeps its own materials.
# Usage: scripts/copy-models.sh [DIR]   (default scenes/real; from anywhere)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-scenes/real}
ENGINE=/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb
SHARED=${RTLAB_SHARED_MODELS:-../shared/models}

die() { echo "copy-models: $*" >&2; exit 1; }
[ -f "$ENGINE" ] || die "$ENGINE is missing: install Debian's assimp-testmodels (scripts/setup)"
[ -f "$SHARED/bunny.obj" ] || die "$SHARED/bunny.obj is missing (set RTLAB_SHARED_MODELS)"
mkdir -p "$OUT"
cp "$ENGINE" "$SHARED/bunny.obj" "$OUT/"
chmod u+w "$OUT"/*  # the shared folder is read-only; a later copy must be able to overwrite
echo "copy-models: $OUT: $(cd "$OUT" && ls | tr '\n' ' ')"
