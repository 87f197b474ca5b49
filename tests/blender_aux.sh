#!/usr/bin/env bash
# share/blender/zdenoise_aux.py renders the auxiliary image of a tiny scene
# (Blender's factory startup: a grey cube, a light, a camera, at 5 % of
# 1920x1080) with Debian's blender, and the file has the passes zdenoise
# --aux finds: Denoising Albedo (the cube's 0.8 grey plus its specular where it is seen, and
# on the background the world's colour, as Cycles' own Denoising Albedo holds it: docs/AUX.md),
# Normal, Depth, the lobe colours and Cryptomatte; zdenoise takes it as --aux with no flags.
set -euo pipefail
build_dir=$1 source_dir=$2
command -v blender >/dev/null || { echo "blender not found (scripts/setup.sh installs it)"; exit 77; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
blender -b --factory-startup -noaudio --python-exit-code 1 \
    -P "$source_dir/share/blender/zdenoise_aux.py" -- -o "$scratch/aux.exr" --samples 2 --percent 5
/usr/bin/python3 - "$scratch/aux.exr" <<'PY'
import sys
import OpenImageIO as oiio
inp = oiio.ImageInput.open(sys.argv[1])
assert inp, oiio.geterror()
spec = inp.spec()
names = list(spec.channelnames)
want = ["ViewLayer.Denoising Albedo." + c for c in "RGB"] \
     + ["ViewLayer.Denoising Normal." + c for c in "XYZ"] + ["ViewLayer.Denoising Depth.Z"] \
     + ["ViewLayer.%s.%s" % (p, c) for p in ("DiffCol", "GlossCol", "TransCol") for c in "RGB"] \
     + ["ViewLayer.CryptoObject00." + c for c in "rgba"]
missing = [n for n in want if n not in names]
assert not missing, "missing passes %s; the file has %s" % (missing, names)
assert (spec.width, spec.height) == (96, 54), (spec.width, spec.height)
px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT).reshape(spec.height, spec.width, -1)
a = names.index("ViewLayer.Denoising Albedo.R")
centre, corner = px[spec.height // 2, spec.width // 2, a], px[1, 1, a]
# Principled base colour 0.8 plus the specular lobe's share (measured 0.857).
assert 0.8 < centre < 0.9, "the cube's albedo is %g, not 0.8-0.9" % centre
# The factory world's colour (0.0509 grey, strength 1).
assert abs(corner - 0.0508761) < 1e-4, "the background's albedo is %g, not the world's 0.0509" % corner
print("passes ok: albedo %.3f at the centre" % centre)
PY
# zdenoise finds the passes with no flags.
"$build_dir/bin/zdenoise" --in "$scratch/aux.exr" --aux "$scratch/aux.exr" \
    -o "$scratch/out.exr" -v 2>&1 | tee "$scratch/log"
grep -q "is the auxiliary image: a Blender Cycles multilayer EXR" "$scratch/log"
