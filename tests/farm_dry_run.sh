#!/usr/bin/env bash
# share/farm/zdenoise-sbatch --dry-run, without Slurm: the task script gets
# the chunks from zdenoise --print-chunks, and the whole list's first and
# last frames as --shot-range, so that --temporal's neighbours of a chunk's
# first and last frames are the frames around the chunk.
#
#   farm_dry_run.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
cli=$(cd "$1" && pwd)/bin/zdenoise
sbatch_script=$(cd "$2" && pwd)/share/farm/zdenoise-sbatch
fail() { echo "FAILED: $*"; echo "$out"; exit 1; }

out=$("$sbatch_script" --dry-run --chunk-size 4 --zdenoise "$cli" -- \
          --in /shot/render.#.exr -o /shot/clean.#.exr --frames 1001-1010 \
          --temporal 1 --static-camera) || { out=; fail "zdenoise-sbatch --dry-run failed"; }
grep -q -- '--array=0-2 ' <<<"$out" || fail "expected an array of 3 tasks"
grep -qx 'chunks=( 1001-1004 1005-1008 1009-1010 )' <<<"$out" || fail "expected chunks of 4 frames"
grep -qx 'shot=1001-1010' <<<"$out" || fail "expected the shot's range 1001-1010"
grep -qF 'exec "$zdenoise" --shot-range "$shot" "${args[@]}" --frames "$chunk"' <<<"$out" \
    || fail "expected the task to run zdenoise with --shot-range and its chunk"
echo "PASSED: 3 chunks, --shot-range 1001-1010"
