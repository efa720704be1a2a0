#!/usr/bin/env bash
# A real Slurm on this one machine renders a frame as a job array of shards plus a merge job (deploy/slurm/, as a
# user submits them), and the merged file must equal a single-process render byte for byte. It installs Debian's
# slurm-wlm and munge when missing, starts munged, slurmctld and slurmd with a configuration of its own (nothing
# in /etc/slurm is touched), and stops them at the end. If a daemon cannot start, it fails with the daemon's log:
# it never passes without the scheduler having run the jobs.
#
#   scripts/slurm-check.sh [--shards N] [--scaling]     (root; after scripts/setup.sh and a release build)
#
# --scaling also times arrays of 1, 2 and 4 shards of a bigger frame (docs/performance.md): a machine shows no
# more speed-up than it has cores.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
shards=4
scaling=
while [ $# -gt 0 ]; do
    case $1 in
        --shards) shards=$2; shift 2 ;;
        --scaling) scaling=1; shift ;;
        *) sed -n '2,12p' "$0" >&2; exit 2 ;;
    esac
done
strata=$repo/target/release/strata
[ -x "$strata" ] || { echo "slurm-check: build strata first: cargo build --release" >&2; exit 1; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    echo "slurm-check: installing slurm-wlm and munge"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
fi

work=$(mktemp -d /tmp/strata-slurm.XXXXXX)
export SLURM_CONF=$work/slurm.conf
node=$(hostname -s)
cpus=$(nproc)
mkdir -p "$work/state" "$work/spool" "$work/munge" "$work/out"
cat > "$SLURM_CONF" <<CONF
ClusterName=strata-check
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=check Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF

# Stops the daemons and waits (up to 20 s) until they have exited: slurmctld writes its state as it shuts down, and
# removing the work directory under it failed once with "Directory not empty".
stop() {
    local pids=() pid
    for pid in "$work/slurmctld.pid" "$work/slurmd.pid" "$work/munge/munged.pid"; do
        [ -f "$pid" ] && pids+=("$(cat "$pid")")
    done
    scontrol shutdown >/dev/null 2>&1 || true
    for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
    for _ in $(seq 200); do
        local alive=0
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
        [ "$alive" = 0 ] && return 0
        sleep 0.1
    done
}
now_ms() { date +%s%3N; }
seconds_since() { awk -v a="$1" -v b="$(now_ms)" 'BEGIN { printf "%.1f", (b - a) / 1000 }'; }
fail() {
    echo "slurm-check: FAILED: $*" >&2
    for log in "$work"/*.log "$work"/out/*.log; do
        [ -f "$log" ] && { echo "--- $log" >&2; tail -n 20 "$log" >&2; }
    done
    stop
    exit 1
}
trap stop EXIT

# munge: Slurm's authentication. A key of this run's own; the daemon runs as root with --force (a check machine).
dd if=/dev/urandom bs=1 count=1024 of="$work/munge/munge.key" 2>/dev/null
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
    --pid-file="$work/munge/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge/seed" \
    || fail "munged did not start"
export MUNGE_SOCKET=$work/munge/socket
# Slurm's munge plugin takes the socket from the configuration, not the environment.
echo "AuthInfo=socket=$work/munge/socket" >> "$SLURM_CONF"

slurmctld -c || fail "slurmctld did not start"
slurmd -c || fail "slurmd did not start"
for _ in $(seq 60); do
    state=$(sinfo -h -N -o %t 2>/dev/null | head -n 1 || true)
    [ "$state" = idle ] && break
    sleep 1
done
[ "${state:-}" = idle ] || fail "the node is '${state:-unknown}', not idle, after a minute"
echo "slurm-check: Slurm $(sinfo -V | awk '{print $2}') is up: node $node with $cpus CPUs"

# The frame: the showcase with indirect light, small enough for a CI machine.
frame=(--size 160x90 --spp 32 --indirect)
scene=$repo/scenes/showcase.toml
"$strata" render "$scene" -o "$work/single.png" "${frame[@]}" --quiet || fail "the single-process render failed"

run_array() { # SHARDS OUTPUT render options...: submits the array and the merge (deploy/slurm/submit.sh), waits
    local n=$1 output=$2 submitted merge state
    shift 2
    submitted=$(cd "$work/out" && STRATA=$strata PARTS_DIR=$work/parts-$n \
        "$repo/deploy/slurm/submit.sh" "$scene" "$output" "$n" "$@") || fail "submitting $n shards failed: $submitted"
    echo "$submitted"
    merge=$(printf '%s\n' "$submitted" | awk '/^merge: job/ {print $3}')
    [ -n "$merge" ] || fail "submit.sh printed no merge job id"
    # Polled here, not with sbatch --wait, whose own polling backs off to 10 s and would swamp the timings.
    while squeue -h -j "$merge" 2>/dev/null | grep -q .; do sleep 0.2; done
    state=$(scontrol show job "$merge" 2>/dev/null | tr ' ' '\n' | awk -F= '$1=="JobState" {print $2}')
    [ "$state" = COMPLETED ] || fail "the merge job $merge ended $state (the array of $n shards or the merge failed)"
}

start=$(now_ms)
run_array "$shards" "$work/merged.png" "${frame[@]}"
took=$(seconds_since "$start")
[ -f "$work/merged.png" ] || fail "the merge job wrote no $work/merged.png"
cmp "$work/single.png" "$work/merged.png" || fail "the merged frame differs from the single-process render"
logs=$(ls "$work"/out/strata-shard-*.log | wc -l)
[ "$logs" -eq "$shards" ] || fail "expected $shards shard logs, found $logs"
echo "slurm-check: $shards shards and their merge ran under Slurm in $took s;" \
    "the merged frame equals the single-process render byte for byte"

# A sequence: the shards split a turntable's frames, each written whole, no merge.
(cd "$work/out" && STRATA=$strata "$repo/deploy/slurm/submit.sh" --wait "$scene" "$work/spin.png" 2 \
    --size 32x18 --spp 2 --turntable 3 >/dev/null) || fail "the turntable array failed"
for n in 1 2 3; do
    [ -f "$work/spin.000$n.png" ] || fail "the turntable array wrote no $work/spin.000$n.png"
done
echo "slurm-check: a turntable of 3 frames over 2 shards wrote every frame"

if [ -n "$scaling" ]; then
    big=(--size 480x270 --spp 64 --indirect)
    t0=$(now_ms); "$strata" render "$scene" -o "$work/big.png" "${big[@]}" --quiet
    echo "slurm-check: scaling on $cpus cores: one process without Slurm $(seconds_since "$t0") s"
    # lavapipe spreads one process over every core already; with one thread per task (LP_NUM_THREADS=1, as a
    # cluster gives each task its own cores) the shards are what spreads the work.
    for threads in all 1; do
        for n in 1 2 4; do
            if [ "$threads" = 1 ]; then export LP_NUM_THREADS=1; else unset LP_NUM_THREADS; fi
            t0=$(now_ms); run_array "$n" "$work/big-$n.png" "${big[@]}" >/dev/null; took=$(seconds_since "$t0")
            unset LP_NUM_THREADS
            cmp "$work/big.png" "$work/big-$n.png" || fail "the $n-shard frame differs"
            rm -f "$work/big-$n.png"
            echo "slurm-check: scaling: lavapipe threads per task: $threads, $n shards: array + merge wall time $took s"
        done
    done
fi
stop
trap - EXIT
rm -rf "$work"
