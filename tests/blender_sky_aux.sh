#!/usr/bin/env bash
# The README's aux workflow on a shot that sees the sky (issue 30): Debian's blender renders
# bench/scenes/exterior_foliage.py (a tree and a railing against a Nishita sky, hard sun
# shadows) small, at 16 spp and as a reference, and share/blender/zdenoise_aux.py its
# auxiliary image from the saved .blend; `zdenoise --aux` must come closer to the
# reference than zdenoise with no flags, by a margin (bench/aux_render.py measures the
# full-size scenes: docs/AUX.md), and keep the sky's light.
set -euo pipefail
build_dir=$1 source_dir=$2
command -v blender >/dev/null || { echo "blender not found (scripts/setup.sh installs it)"; exit 77; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
scene=$source_dir/bench/scenes/exterior_foliage.py
blender=(blender -b --factory-startup -noaudio --python-exit-code 1)
res=(--res 128 128 --threads 2)
"${blender[@]}" --python "$scene" -- "${res[@]}" --spp 16 --seed 1 --out "$scratch/render.exr" \
    --save-blend "$scratch/shot.blend" > "$scratch/log_render" 2>&1 || { tail "$scratch/log_render"; exit 1; }
"${blender[@]}" --python "$scene" -- "${res[@]}" --spp 512 --seed 1000 --depth 32 \
    --out "$scratch/ref.exr" > "$scratch/log_ref" 2>&1 || { tail "$scratch/log_ref"; exit 1; }
"${blender[@]}" "$scratch/shot.blend" -P "$source_dir/share/blender/zdenoise_aux.py" -- \
    -o "$scratch/aux.exr" > "$scratch/log_aux" 2>&1 || { tail "$scratch/log_aux"; exit 1; }
zdenoise=$build_dir/bin/zdenoise
"$zdenoise" --in "$scratch/render.exr" -o "$scratch/none.exr"
"$zdenoise" --in "$scratch/render.exr" --aux "$scratch/aux.exr" -o "$scratch/aux_out.exr" -v \
    | tee "$scratch/log_zdenoise"
grep -q "albedo    the render's own used at" "$scratch/log_zdenoise"
/usr/bin/python3 - "$scratch" <<'PY'
import sys
import numpy as np
import OpenImageIO as oiio
d = sys.argv[1]


def planes(name):
    inp = oiio.ImageInput.open(f"{d}/{name}")
    assert inp, oiio.geterror()
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT).reshape(spec.height, spec.width, -1)
    return px, list(spec.channelnames)


def rgb(name):
    px, names = planes(name)
    return px[..., [names.index(f"ViewLayer.Combined.{c}") for c in "RGB"]]


def relmse(x):  # as shared/tools/zmetrics.py
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 1e-2)))


ref = rgb("ref.exr")
px, names = planes("render.exr")
sky = px[..., names.index("ViewLayer.Denoising Depth.Z")] == 0
none, aux = relmse(rgb("none.exr")), relmse(rgb("aux_out.exr"))
print(f"relMSE against 512 spp: no flags {none:.5f}, --aux {aux:.5f} ({aux / none:.2f}x); "
      f"sky {100 * sky.mean():.1f} % of the pixels")
assert sky.mean() > 0.1, "the shot shows too little sky to test anything"
assert aux <= 0.85 * none, "--aux is not at least 15 % better than no flags"
out, want = rgb("aux_out.exr")[sky].mean(), ref[sky].mean()
assert abs(out / want - 1) < 0.02, f"the sky's mean light is {out:.4f}, the reference's {want:.4f}"
print("ok: --aux beats no aux on a shot that sees the sky")
PY
