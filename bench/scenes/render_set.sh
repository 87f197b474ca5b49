#!/usr/bin/env bash
# render_set.sh - the benchmark set of one or more scenes of bench/scenes/, laid out as
# shared/data is (bench/aux_render.py --data, bench/aux.py, bench/bench.py read it):
#
#   OUT/<scene>/<scene>_spp<S>_s<seed>.exr   the noisy renders (SPP x SEEDS)
#   OUT/<scene>/<scene>_ref.exr              the reference: REF_SPP samples, float, seed 1000
#   OUT/<scene>/<scene>_albedo.exr           its Denoising Albedo as plain float R,G,B
#   OUT/<scene>.blend                        the 16-spp scene set up (aux_render.py --blends)
#
# Usage: bench/scenes/render_set.sh OUT SCENE... ; environment: SPP ("4 16 64"), SEEDS ("1 2"),
#        REF_SPP (4096, as the public set's references), RES ("384 384"), BLENDER (blender). Existing files are kept, so an
#        interrupted run goes on where it stopped.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=$1
shift
spp=${SPP:-4 16 64} seeds=${SEEDS:-1 2} ref_spp=${REF_SPP:-4096} res=${RES:-384 384}
blender=${BLENDER:-blender}
render() {  # scene out.exr extra-args...
    local scene=$1 file=$2
    shift 2
    [ -s "$file" ] && return 0
    "$blender" -b --factory-startup -noaudio --python-exit-code 1 \
        --python "$here/$scene.py" -- --res $res --out "$file.tmp.exr" "$@" > "$file.log" 2>&1 \
        || { echo "render_set.sh: $scene failed, see $file.log" >&2; exit 1; }
    mv "$file.tmp.exr" "$file"
    rm -f "$file.log"
}
for scene in "$@"; do
    [ -f "$here/$scene.py" ] || { echo "render_set.sh: no scene $here/$scene.py" >&2; exit 2; }
    d=$out/$scene
    mkdir -p "$d"
    if [ ! -s "$out/$scene.blend" ]; then
        render "$scene" "$d/blend_probe.exr" --spp 16 --seed 1 --save-blend "$out/$scene.blend"
        rm -f "$d/blend_probe.exr"
    fi
    for s in $seeds; do
        for n in $spp; do
            render "$scene" "$d/${scene}_spp${n}_s$s.exr" --spp "$n" --seed "$s"
        done
    done
    render "$scene" "$d/${scene}_ref.exr" --spp "$ref_spp" --seed 1000 --depth 32
    [ -s "$d/${scene}_albedo.exr" ] || oiiotool "$d/${scene}_ref.exr" \
        --ch "R=ViewLayer.Denoising Albedo.R,G=ViewLayer.Denoising Albedo.G,B=ViewLayer.Denoising Albedo.B" \
        --eraseattrib "cryptomatte.*" -d float --compression zip -o "$d/${scene}_albedo.exr"
    echo "render_set.sh: $d"
done
