#!/usr/bin/env bash
# Install the build tree into a scratch prefix; the installed plugin, found
# through OIIO_LIBRARY_PATH alone, must read a recipe written by the
# installed zdenoise (its RPATH must find the installed libzdenoise).
set -euo pipefail
build_dir=$1 source_dir=$2
command -v iinfo >/dev/null || { echo "iinfo not found (openimageio-tools)"; exit 77; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cmake --install "$build_dir" --prefix "$scratch/prefix" >/dev/null
plugin=$(find "$scratch/prefix" -name zdenoise.imageio.so)
[ -n "$plugin" ] || { echo "zdenoise.imageio.so not installed"; exit 1; }
# A recipe reads files in its own folder (share/zdn-format.md).
cp "$source_dir/share/samples/cornell_textured_spp16_crop.exr" "$scratch/shot.exr"
"$scratch/prefix/bin/zdenoise" --in "$scratch/shot.exr" --write-recipe "$scratch/shot.zdn"
# ZDENOISE_HOST_ENV: in a sanitized build, the sanitizer runtime iinfo must
# preload to load the plugin (tests/CMakeLists.txt); words of VAR=value.
# shellcheck disable=SC2086
info=$(env -u LD_LIBRARY_PATH ${ZDENOISE_HOST_ENV:-} \
       OIIO_LIBRARY_PATH="$(dirname "$plugin")" iinfo "$scratch/shot.zdn")
echo "$info"
grep -q "96 x   96, 54 channel, float zdenoise" <<<"$info"
