#!/usr/bin/env bash
# share/blender/zdenoise_addon.py in Debian's blender: the add-on installed in a
# BLENDER_USER_SCRIPTS folder and enabled with --addons denoises a tiny Cycles
# scene after bpy.ops.render.render() (tests/blender_addon_test.py checks the
# image 'zdenoise', the output path, the auxiliary render, the errors), then
# after each frame of `blender -b scene.blend -f 2` and `-a`. Nothing is written
# but the output paths the scene names (TMPDIR is the scratch's own, and must
# be left empty).
set -euo pipefail
build_dir=$1 source_dir=$2
source "$source_dir/tests/blender_addon_scratch.sh"
blender=(blender -b --factory-startup -noaudio --python-exit-code 1)

"${blender[@]}" --addons zdenoise_addon -P "$source_dir/tests/blender_addon_test.py" -- "$scratch"

# The command-line renders: render_post runs after each frame there too.
"${blender[@]}" "$scratch/scene.blend" --addons zdenoise_addon -f 2 2>&1 | tee "$scratch/log_f"
grep -q "zdenoise: Frame 2 denoised" "$scratch/log_f"
rm "$scratch/frames/f_0002.exr" "$scratch/frames/render_0002.png"
"${blender[@]}" "$scratch/scene.blend" --addons zdenoise_addon -a 2>&1 | tee "$scratch/log_a"
for f in 1 2; do grep -q "zdenoise: Frame $f denoised" "$scratch/log_a"; done
/usr/bin/python3 - "$scratch" <<'PY'
import os, sys
import OpenImageIO as oiio
scratch = sys.argv[1]
frames = sorted(os.listdir(os.path.join(scratch, "frames")))
want = ["f_0001.exr", "f_0002.exr", "render_0001.png", "render_0002.png"]
assert frames == want, "frames/ holds %s, not %s" % (frames, want)
for f in want[:2]:
    spec = oiio.ImageInput.open(os.path.join(scratch, "frames", f)).spec()
    assert (spec.width, spec.height) == (64, 64), (f, spec.width, spec.height)
    assert "ViewLayer.Combined.R" in spec.channelnames, spec.channelnames
    assert spec.get_string_attribute("zdenoise.version"), "%s: not written by zdenoise" % f
work = os.listdir(os.path.join(scratch, "work"))
tmp = os.listdir(os.path.join(scratch, "tmp"))
assert not work, "files in the working folder: %s" % work
assert not tmp, "files left in TMPDIR: %s" % tmp
print("-f and -a: %s" % ", ".join(frames))
PY
