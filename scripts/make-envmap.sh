#!/usr/bin/env bash
# Makes the six 64x64 cubemap faces of scenes/envmap.json in scenes/env/ with oiiotool
# (openimageio-tools). Each face is a checkerboard in its own colour with white "dice pips":
# +x 1 pip (red), -x 2 (cyan), +y 3 (sky blue), -y 4 (brown), +z 5 (green), -z 6 (purple),
# so every face and its orientation can be recognised in reflections.
# Usage: scripts/make-envmap.sh   (from anywhere; overwrites scenes/env/*.png)
set -euo pipefail
cd "$(dirname "$0")/../scenes/env"

# Pip centres on a 64x64 face (dice layout), as "x,y".
TL=16,16; TR=48,16; ML=16,32; C=32,32; MR=48,32; BL=16,48; BR=48,48
pips() {  # -> oiiotool --box arguments for the given pip centres (8x8 white squares)
  for p in "$@"; do
    x=${p%,*}; y=${p#*,}
    printf -- '--box:color=1,1,1:fill=1 %d,%d,%d,%d ' $((x - 4)) $((y - 4)) $((x + 3)) $((y + 3))
  done
}
face() {  # name color1 color2 pip...
  local name=$1 c1=$2 c2=$3; shift 3
  # shellcheck disable=SC2046
  oiiotool --pattern "checker:width=8:height=8:color1=$c1:color2=$c2" 64x64 3 \
    $(pips "$@") -d uint8 -o "$name.png"
}
face px 0.80,0.12,0.08 0.40,0.06,0.04 $C
face nx 0.08,0.70,0.75 0.04,0.35,0.38 $TL $BR
face py 0.30,0.50,0.95 0.15,0.25,0.50 $TL $C $BR
face ny 0.45,0.30,0.15 0.22,0.15,0.07 $TL $TR $BL $BR
face pz 0.15,0.70,0.15 0.07,0.35,0.07 $TL $TR $C $BL $BR
face nz 0.55,0.15,0.70 0.27,0.07,0.35 $TL $TR $ML $MR $BL $BR
