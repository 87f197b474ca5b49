#!/usr/bin/env bash
# Install what zdenoise needs to build and test, from Debian's packages.
# Installs only what is missing; needs root (or sudo) when something is.
set -euo pipefail
packages=(g++ cmake make pkg-config libopenimageio-dev libopenexr-dev
          openimageio-tools python3-openimageio nlohmann-json3-dev libgtest-dev
          libopencolorio-dev opencolorio-tools libbenchmark-dev
          # Google Highway: the filter's vector kernels, dispatched at run time
          libhwy-dev
          # the Python module (python/) and its tests
          pybind11-dev python3-dev python3-numpy
          # the fuzz targets (scripts/fuzz.sh, CI)
          clang libclang-rt-14-dev
          # share/blender/zdenoise_aux.py, zdenoise_addon.py and their BlenderAux, BlenderAddon tests
          blender
          # for the SlurmFarm test only: a one-node Slurm on localhost
          slurmctld slurmd slurm-client munge)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" \
        || missing+=("$p")
done
if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -q
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
else
    echo "setup: all dependencies present"
fi
