#!/usr/bin/env bash
# peers/mitsuba/repack-wheels.sh — shrinks the mitsuba 3.9.1 wheel to what the Mitsuba peer
# (peers/mitsuba/) loads, so that the wheels can travel to the GPU host (no internet there) in the
# repository's ignored .whl/ folder: well under 60 MB instead of 68 MB.
#
# Kept: the variants cuda_ad_rgb and llvm_ad_rgb (and scalar_rgb, which mitsuba's Python code may
# import for scalar types), every shared library they link (libmitsuba, Embree, OpenEXR, png,
# jpeg, pugixml, nanobind, struct-jit) and the plugins in KEEP_PLUGINS: those the peer's scenes
# instantiate (ellipsoids, sphere, rectangle, the meshes' default diffuse BSDF with its uniform
# texture, merge) plus the defaults a scene dictionary falls back to (path, perspective, hdrfilm,
# independent, box, gaussian, srgb, bitmap). A plugin .so holds all variants; it is kept or
# dropped whole. Dropped: the other 10 variants' Python modules, the other plugins, C++
# headers, type stubs, and data/srgb.coeff and data/sunsky (spectral upsampling and sky models,
# which RGB variants of the peer never read). The drjit wheel is kept whole (5 MB).
#
# RECORD is rewritten without the removed files (the kept files' hashes are unchanged), so pip
# installs the result like the original. The wheel's name is unchanged.
#
# Usage: peers/mitsuba/repack-wheels.sh [DIR]     (DIR holds the downloaded wheels; default .whl)
#   Download first, from the repository root:
#   python3 -m pip download --no-deps --only-binary=:all: --python-version 3.12 \
#     --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 \
#     --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d .whl \
#     mitsuba==3.9.1 drjit==1.5.0
set -euo pipefail
DIR=${1:-.whl}
shopt -s nullglob
wheels=("$DIR"/mitsuba-*.whl)
[ ${#wheels[@]} -eq 1 ] || { echo "repack-wheels.sh: expected one mitsuba wheel in $DIR, found ${#wheels[@]}" >&2; exit 1; }
[ -n "$(echo "$DIR"/drjit-*.whl)" ] || { echo "repack-wheels.sh: no drjit wheel in $DIR" >&2; exit 1; }

KEEP_VARIANTS="cuda_ad_rgb llvm_ad_rgb scalar_rgb"
KEEP_PLUGINS="ellipsoids sphere rectangle diffuse uniform merge path perspective hdrfilm independent box gaussian srgb bitmap"

python3 - "${wheels[0]}" "$KEEP_VARIANTS" "$KEEP_PLUGINS" <<'EOF'
import os, re, sys, zipfile
path, variants, plugins = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
ALL_VARIANTS = re.compile(r"^mitsuba/((?:scalar|llvm|cuda)_[a-z_]+)\.cpython-[^/]+\.so$")

def keep(name):
    m = ALL_VARIANTS.match(name)
    if m:
        return m.group(1) in variants
    if name.startswith("mitsuba/plugins/"):
        return os.path.splitext(os.path.basename(name))[0] in plugins
    if name.startswith(("mitsuba/include/", "mitsuba/mitsuba_stubs/")) or name.endswith(".pyi"):
        return False
    if name in ("mitsuba/data/srgb.coeff",) or name.startswith("mitsuba/data/sunsky"):
        return False
    return True

tmp = path + ".tmp"
before = os.path.getsize(path)
with zipfile.ZipFile(path) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED,
                                                      compresslevel=9) as dst:
    names = src.namelist()
    kept = [n for n in names if keep(n)]
    if len(kept) == len(names):
        print(f"repack-wheels.sh: {path} is already repacked")
    for n in kept:
        data = src.read(n)
        if n.endswith(".dist-info/RECORD"):
            lines = data.decode().splitlines()
            data = ("\n".join(l for l in lines if l.split(",")[0] in kept) + "\n").encode()
        info = src.getinfo(n)
        zi = zipfile.ZipInfo(n, date_time=info.date_time)
        zi.external_attr = info.external_attr
        zi.compress_type = zipfile.ZIP_DEFLATED
        dst.writestr(zi, data)
os.replace(tmp, path)
print(f"repack-wheels.sh: {os.path.basename(path)}: {before / 1e6:.1f} MB -> "
      f"{os.path.getsize(path) / 1e6:.1f} MB, {len(names) - len(kept)} of {len(names)} files dropped")
EOF
du -ch "$DIR"/*.whl | tail -1
