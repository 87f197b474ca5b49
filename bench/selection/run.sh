#!/bin/sh
# run.sh SCENE SPP PREFIX: the session-7 selection prototype on one public case, the
# reference as --aux (bench/results/2026-12-selection-log.md section 8). Writes PREFIX_* in the current folder.
set -e
HERE=$(cd "$(dirname "$0")" && pwd)
SHARED=${ZDENOISE_SHARED:-$HERE/../../../shared}
Z=${ZDENOISE:-$HERE/../../build/bin/zdenoise}
S=$1; P=$2; T=$3; D=$SHARED/data/$S
# --diagnostics adds zdenoise.noise (select.py --sigma filter) and moves no pixel.
$Z --in $D/${S}_spp${P}_s1.exr --aux $D/${S}_ref.exr --diagnostics -o ${T}_k0.exr > /dev/null
/usr/bin/python3 $HERE/perturb.py $S $P ${T}_pert.exr 0.1 > /dev/null
$Z --in ${T}_pert.exr --aux $D/${S}_ref.exr -o ${T}_k0p.exr > /dev/null
/usr/bin/python3 $HERE/feature_regression.py $S $P ${T}.npy
/usr/bin/python3 $HERE/select.py $S $P $T --sigma pair
/usr/bin/python3 $HERE/select.py $S $P $T --sigma filter
