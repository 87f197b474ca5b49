#!/usr/bin/env bash
# Same output, bit for bit: runs two zdenoise builds on the public set (both
# seeds, 4/16/64 spp, no flags), a few modes and options on one file, a
# temporal sequence and the 1080p frame, and compares each pair of outputs
# with idiff (-fail 0 -warn 0). For changes that promise no behaviour
# change (a refactor). Prints one line per case and exits non-zero at the
# first difference's end of run.
#   bench/same_output.sh OLD_ZDENOISE NEW_ZDENOISE [DATA]   (DATA: ../shared/data)
set -uo pipefail
old=$1 new=$2
data=$(cd "${3:-$(dirname "$0")/../../shared/data}" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
status=0
run_case() {  # name, then zdenoise's arguments without -o
    local name=$1; shift
    "$old" "$@" -o "$work/old.exr" >/dev/null 2>"$work/old.err" || { echo "$name: old build failed: $(tail -1 "$work/old.err")"; status=1; return; }
    "$new" "$@" -o "$work/new.exr" >/dev/null 2>"$work/new.err" || { echo "$name: new build failed: $(tail -1 "$work/new.err")"; status=1; return; }
    if idiff -q -fail 0 -warn 0 "$work/old.exr" "$work/new.exr" >/dev/null 2>&1; then
        echo "$name: identical"
    else
        echo "$name: DIFFERENT"; status=1
    fi
}
for scene in cornell_textured newspaper zigzag_steps; do
    for s in 1 2; do
        for spp in 4 16 64; do
            run_case "${scene}_spp${spp}_s$s" --in "$data/$scene/${scene}_spp${spp}_s$s.exr"
        done
    done
done
f=$data/newspaper/newspaper_spp16_s1.exr
run_case "layers" --in "$f" --mode layers
run_case "path" --in "$f" --mode path
run_case "clean albedo" --in "$f" --aux "$data/newspaper/newspaper_albedo.exr"
run_case "halves" --in "$f" --halves "$f" "$data/newspaper/newspaper_spp16_s2.exr"
run_case "select 0, rmax 4" --in "$f" --select 0 --rmax 4
mkdir "$work/seq"
for i in 1 2 3; do
    ln -s "$data/cornell_textured/cornell_textured_spp16_s$(( (i % 2) + 1 )).exr" "$work/seq/f.000$i.exr"
done
for who in old new; do
    "${!who}" --in "$work/seq/f.#.exr" --frames 1-3 --temporal 1 --static-camera \
        -o "$work/seq/$who.#.exr" >/dev/null 2>"$work/$who.err" || echo "temporal: $who build failed: $(tail -1 "$work/$who.err")"
done
for i in 1 2 3; do
    if idiff -q -fail 0 -warn 0 "$work/seq/old.000$i.exr" "$work/seq/new.000$i.exr" >/dev/null 2>&1; then
        echo "temporal frame $i: identical"
    else
        echo "temporal frame $i: DIFFERENT"; status=1
    fi
done
run_case "1080p" --in "$data/perf/cornell_1080p_spp16.exr"
exit $status
