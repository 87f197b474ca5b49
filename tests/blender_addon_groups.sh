#!/usr/bin/env bash
# share/blender/zdenoise_addon.py and light groups in Debian's blender: the add-on, enabled
# with --addons from a temporary BLENDER_USER_SCRIPTS, renders a tiny Cycles scene with the
# light groups key and fill (tests/blender_addon_groups_test.py checks the images
# 'zdenoise <group>' and the compositor's nodes). TMPDIR is the scratch's own and must be
# left empty.
set -euo pipefail
build_dir=$1 source_dir=$2
source "$source_dir/tests/blender_addon_scratch.sh"
blender -b --factory-startup -noaudio --python-exit-code 1 --addons zdenoise_addon \
    -P "$source_dir/tests/blender_addon_groups_test.py" -- "$scratch"
leftovers=$(find "$scratch/tmp" "$scratch/work" -mindepth 1)
[ -z "$leftovers" ] || { echo "files left behind: $leftovers"; exit 1; }
