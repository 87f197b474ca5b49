#!/usr/bin/env bash
# The farm dispatch, proved on a real Slurm: a single-node cluster on
# localhost from Debian's packages (slurmctld, slurmd, munge), private to
# this test (own munge key and socket, own ports, own state folder), runs
# share/farm/zdenoise-sbatch on a 6-frame sequence in 3 chunks; the
# outputs must be bit-identical to a local run. Exit 77 (skipped) with a
# message where Slurm cannot run: not installed, or not root.
#
#   slurm_farm.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
source=$(cd "$2" && pwd)
cli=$build/bin/zdenoise
sbatch_script=$source/share/farm/zdenoise-sbatch

skip() { echo "SKIPPED: $*"; exit 77; }
for program in slurmctld slurmd munged sbatch squeue sinfo; do
    command -v "$program" >/dev/null || [ -x "/usr/sbin/$program" ] \
        || skip "$program not found (Debian packages slurmctld slurmd slurm-client munge; scripts/setup.sh installs them)"
done
[ "$(id -u)" -eq 0 ] || skip "slurmd must run as root to start jobs; run this test as root (as CI does)"
PATH=$PATH:/usr/sbin

work=$(mktemp -d "${TMPDIR:-/tmp}/zdenoise_slurm.XXXXXX")
pids=()
cleanup() {
    for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$pid" 2>/dev/null || true
    done
    rm -rf "$work"
}
trap cleanup EXIT
fail() {
    echo "FAILED: $*"
    for log in "$work"/*.log "$work"/slurm-*.out; do
        [ -f "$log" ] && { echo "---- $log"; tail -n 20 "$log"; }
    done
    exit 1
}
# Wait up to $1 seconds for the command after it to succeed.
wait_for() {
    local seconds=$1; shift
    for _ in $(seq $((seconds * 4))); do "$@" >/dev/null 2>&1 && return 0; sleep 0.25; done
    return 1
}

# munge with its own key and socket.
mkdir -p "$work/munge" "$work/spool" "$work/state" "$work/frames"
chmod 755 "$work/munge"  # the socket must be reachable; the key stays 600
head -c 1024 /dev/urandom >"$work/munge/munge.key"
chmod 600 "$work/munge/munge.key"
munged --foreground --force --key-file="$work/munge/munge.key" \
    --socket="$work/munge/munge.socket" --pid-file="$work/munge/munged.pid" \
    --seed-file="$work/munge/munge.seed" >"$work/munged.log" 2>&1 &
pids+=($!)
wait_for 10 test -S "$work/munge/munge.socket" || fail "munged did not start"

# A one-node cluster on ports nobody else uses.
port=$((20000 + RANDOM % 20000))
node=$(hostname -s)
cpus=$(nproc)
export SLURM_CONF=$work/slurm.conf
cat >"$SLURM_CONF" <<CONF
ClusterName=zdenoisetest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/munge.socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=10 State=UP
CONF
slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out.log" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" >"$work/slurmd.out.log" 2>&1 &
pids+=($!)
idle() { sinfo -h -N -o '%t' | grep -qx idle; }
wait_for 60 idle || fail "the Slurm node did not come up idle: $(sinfo -N 2>&1 | tr '\n' ' ')"

# Six frames (the bundled sample, each frame scaled differently).
sample=$source/share/samples/cornell_textured_spp16_crop.exr
for f in 1001 1002 1003 1004 1005 1006; do
    oiiotool "$sample" --mulc "0.$((f - 1000))1" -o "$work/frames/shot.$f.exr" \
        || fail "oiiotool could not write frame $f"
done
args=(--in "$work/frames/shot.#.exr" --frames 1001-1006 --threads 1)
"$cli" "${args[@]}" -o "$work/frames/local.#.exr" 2>"$work/local.log" \
    || fail "the local run failed"

job=$("$sbatch_script" --chunk-size 2 --zdenoise "$cli" \
          --sbatch-arg "--output=$work/slurm-%A_%a.out" --sbatch-arg --cpus-per-task=1 \
          -- "${args[@]}" -o "$work/frames/farm.#.exr") || fail "zdenoise-sbatch failed"
echo "submitted job array $job"
finished() { [ -z "$(squeue -h -j "$job" 2>/dev/null)" ]; }
wait_for 150 finished || fail "job $job did not finish in 150 s: $(squeue 2>&1 | tr '\n' ' ')"

tasks=$(ls "$work"/slurm-"$job"_*.out 2>/dev/null | wc -l)
[ "$tasks" -eq 3 ] || fail "expected 3 array tasks (chunks of 2 frames), found $tasks logs"
grep -q "frames 1003-1004" "$work/slurm-${job}_1.out" || fail "task 1 did not get frames 1003-1004"
for f in 1001 1002 1003 1004 1005 1006; do
    [ -f "$work/frames/farm.$f.exr" ] || fail "frame $f was not written by the farm"
    cmp -s "$work/frames/local.$f.exr" "$work/frames/farm.$f.exr" \
        || fail "frame $f from the farm differs from the local run"
done
echo "PASSED: 6 frames in 3 Slurm array tasks, bit-identical to the local run"
