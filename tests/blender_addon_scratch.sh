# Sourced by the add-on's tests (blender_addon.sh, blender_addon_groups.sh) with $build_dir
# and $source_dir set: skips (exit 77) without blender; makes $scratch, removed on exit,
# with the add-on linked into $scratch/scripts/addons (BLENDER_USER_SCRIPTS), TMPDIR in
# $scratch/tmp and the working folder $scratch/work, where it cds; zdenoise is the build's.
command -v blender >/dev/null || { echo "blender not found (scripts/setup.sh installs it)"; exit 77; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
mkdir -p "$scratch/scripts/addons" "$scratch/tmp" "$scratch/work"
ln -s "$source_dir/share/blender/zdenoise_addon.py" "$scratch/scripts/addons/zdenoise_addon.py"
export BLENDER_USER_SCRIPTS=$scratch/scripts
export ZDENOISE_EXECUTABLE=$build_dir/bin/zdenoise
export TMPDIR=$scratch/tmp
cd "$scratch/work"
