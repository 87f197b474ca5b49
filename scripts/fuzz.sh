#!/usr/bin/env bash
# Build the libFuzzer targets (clang, in build-fuzz/) and run each for
# SECONDS (default 60) from its seeds in tests/fuzz/corpus. Inputs found on
# the way go to a temporary folder, so the committed seeds stay as they
# are; a crash leaves its input as crash-* in the current folder and fails
# the run. Only the targets and what they link are built;
# ZDENOISE_BUILD_JOBS parallel jobs (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
# -O1 as the sanitized build (.ci/run): the compile is the run's cost, a
# third shorter than -O2's; a short run finds the same things.
cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DZDENOISE_FUZZ=ON \
      -DZDENOISE_BUILD_TESTS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g -DNDEBUG" >/dev/null
targets=(channel_spec denoise frames recipe)
cmake --build build-fuzz -j"${ZDENOISE_BUILD_JOBS:-2}" --target "${targets[@]/#/fuzz_}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for target in "${targets[@]}"; do
    mkdir "$work/$target"
    if ! build-fuzz/bin/fuzz_$target -max_total_time="$seconds" -print_final_stats=1 \
            "$work/$target" tests/fuzz/corpus/$target >"$work/$target.log" 2>&1; then
        tail -n 40 "$work/$target.log"
        echo "fuzz: fuzz_$target failed (its input is in crash-*)" >&2
        exit 1
    fi
    echo "fuzz: fuzz_$target ${seconds}s, $(grep -o 'number_of_executed_units: [0-9]*' "$work/$target.log")"
done
