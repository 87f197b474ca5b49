#!/usr/bin/env bash
# Install the build tree into a scratch prefix; the installed Python module,
# found through PYTHONPATH at its install folder alone, must load (its RPATH
# finds the installed libzdenoise, its colour code the installed OCIO config)
# and write the file the installed zdenoise writes.
# Arguments: the build folder, the source folder, the module's folder
# relative to the prefix (ZDENOISE_PYTHON_INSTALL_DIR), its interpreter.
set -euo pipefail
build_dir=$1 source_dir=$2 site=$3 python=$4
case $site in
    /*) echo "ZDENOISE_PYTHON_INSTALL_DIR is absolute ($site): not in a scratch prefix"; exit 77 ;;
esac
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cmake --install "$build_dir" --prefix "$scratch/prefix" >/dev/null
module=$(find "$scratch/prefix" -name 'zdenoise.cpython-*.so')
[ -n "$module" ] || { echo "the Python module is not installed"; exit 1; }
[ "$(dirname "$module")" = "$scratch/prefix/$site" ] \
    || { echo "installed as $module, not in <prefix>/$site"; exit 1; }
sample="$scratch/prefix/share/zdenoise/samples/cornell_textured_spp16_crop.exr"
"$scratch/prefix/bin/zdenoise" --in "$sample" -o "$scratch/cmd.exr" --eta 0.03
# ZDENOISE_HOST_ENV: in a sanitized build, the sanitizer runtime python3
# must preload to load the module (tests/CMakeLists.txt); words of VAR=value.
# shellcheck disable=SC2086
env -u LD_LIBRARY_PATH ${ZDENOISE_HOST_ENV:-} PYTHONPATH="$scratch/prefix/$site" \
    "$python" -c '
import sys, zdenoise
assert zdenoise.__file__.startswith(sys.argv[1]), zdenoise.__file__
stats = zdenoise.denoise_file(sys.argv[2], sys.argv[3], eta=0.03)
print(zdenoise.__file__, stats["log"][1])
' "$scratch/prefix/" "$sample" "$scratch/py.exr"
cmp "$scratch/cmd.exr" "$scratch/py.exr"
