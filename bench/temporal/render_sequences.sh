#!/bin/bash
# render_sequences.sh [DIR] - render the temporal benchmark sequences (see README.md).
#   DIR/static.0001-0008.exr, DIR/pan.0001-0008.exr   16 spp, seed = frame number
#   DIR/static_ref.0004.exr, DIR/pan_ref.0004.exr, DIR/pan_ref.0005.exr
#                                                      REF_SPP (default 1024) spp, seed = 1000 + frame
# Environment: BLENDER (default blender), SPP (16), REF_SPP (1024), FRAMES (8).
# One Blender process at a time; stops at the first failure.
set -euo pipefail
DIR=${1:-/tmp/zdenoise_temporal}
BLENDER=${BLENDER:-blender}
SPP=${SPP:-16}
REF_SPP=${REF_SPP:-1024}
FRAMES=${FRAMES:-8}
SCENE="$(cd "$(dirname "$0")" && pwd)/sequence_scene.py"
mkdir -p "$DIR"

run() {  # run ARGS... : one Blender render; full log appended to DIR/render.log
    echo "== $*" | tee -a "$DIR/render.log"
    "$BLENDER" -b --factory-startup -noaudio --python-exit-code 1 --python "$SCENE" -- "$@" 2>&1 \
        | tee -a "$DIR/render.log" | grep --line-buffered '^sequence_scene:' \
        || { echo "render failed, see $DIR/render.log" >&2; exit 1; }
}

for motion in static pan; do
    run --motion "$motion" --frames "$FRAMES" --first 1 --spp "$SPP" --out-pattern "$DIR/$motion.####.exr"
done
run --motion static --only-frame 4 --spp "$REF_SPP" --seed-offset 1000 --out-pattern "$DIR/static_ref.####.exr"
run --motion pan --only-frame 4 --spp "$REF_SPP" --seed-offset 1000 --out-pattern "$DIR/pan_ref.####.exr"
run --motion pan --only-frame 5 --spp "$REF_SPP" --seed-offset 1000 --out-pattern "$DIR/pan_ref.####.exr"
ls -l "$DIR"/*.exr
