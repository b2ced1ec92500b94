#!/usr/bin/env bash
# test_cluster.sh -- the offline half of docs/deploy.md on a real one-node Slurm cluster (Debian's
# slurm-wlm and munge), started here in a temporary directory with its own configuration, ports,
# munge key, socket and spool; no system service or file outside that directory is touched, and
# everything started is stopped at the end. `make test-cluster` runs it (not part of `make test`).
#  1. deploy/slurm/submit-render.sh queues the Cornell orbit as 4 array tasks and the merge after
#     them: the merged frames are byte-identical to one process's, render.json and the MP4 exist.
#  2. deploy/slurm/refs.sbatch renders a short bench's references as 2 array tasks into one cache:
#     the bench then renders no reference.
# Prints the wall time of the 4 segments (with the merge) against one process.
# Usage: test_cluster.sh IIRD SOURCE_DIR; exit 0 passed, 1 failed, 77 Slurm could not start.
set -u
iird=$(realpath "$1")
src=$(realpath "$2")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/iird-cluster-XXXXXX")
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
    wait 2>/dev/null
    rm -rf "$tmp"
}
trap cleanup EXIT
skip() { echo "SKIP: Slurm could not start here: $*"; exit 77; }

for prog in munged munge slurmctld slurmd sbatch squeue sinfo; do
    command -v $prog >/dev/null || skip "$prog is missing (make test-cluster installs slurm-wlm and munge)"
done

# ---- munge: a key and a socket of our own ----
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log" "$tmp/jobs" "$tmp/out"
chmod 711 "$tmp" "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 2>/dev/null
chmod 400 "$tmp/munge/munge.key"
sock=$tmp/munge/socket
munged -F --force --socket="$sock" --key-file="$tmp/munge/munge.key" --pid-file="$tmp/munge/pid" \
    --log-file="$tmp/log/munged.log" --seed-file="$tmp/munge/seed" >"$tmp/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$sock" ] && break; sleep 0.1; done
munge -S "$sock" -n | unmunge -S "$sock" >/dev/null 2>&1 || skip "munged: $(tail -3 "$tmp/log/munged.out")"

# ---- slurm: one node, two free ports, no cgroups or accounting ----
port=$(python3 -c "import socket; s = socket.socket(); s.bind(('127.0.0.1', 0)); print(s.getsockname()[1])")
node=$(hostname)
cat >"$tmp/slurm.conf" <<CONF
ClusterName=iirtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$(id -un)
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
ReturnToService=2
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=iirtest Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$tmp/slurm.conf IIRD=$iird OMP_NUM_THREADS=2
slurmctld -D -i >"$tmp/log/slurmctld.out" 2>&1 &
pids+=($!)
sleep 1
slurmd -D >"$tmp/log/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do sinfo -h -o %T 2>/dev/null | grep -q idle && break; sleep 0.2; done
sinfo -h -o %T 2>/dev/null | grep -q idle ||
    skip "the node did not come up: $(tail -3 "$tmp/log/slurmctld.log" "$tmp/log/slurmd.log" 2>/dev/null)"

# waits until the queue is empty (at most $1 s)
drain_queue() {
    for _ in $(seq $(($1 * 5))); do [ -z "$(squeue -h 2>/dev/null)" ] && return 0; sleep 0.2; done
    return 1
}

# ---- 1. an animation as 4 segments and the merge ----
args=(--anim orbit --size 96x72 --sm-res 32 --scenes "$src/scenes")
t0=${EPOCHREALTIME/./}
"$iird" render "${args[@]}" --out "$tmp/one" >/dev/null 2>&1 || fail "one process render"
t1=${EPOCHREALTIME/./}
cd "$tmp/jobs"
out=$("$src/deploy/slurm/submit-render.sh" 4 --video "$tmp/out/orbit.mp4" -- "${args[@]}" --out "$tmp/out/orbit" 2>&1) ||
    fail "submit-render.sh: $out"
drain_queue 300 || fail "the render jobs did not finish: $(squeue 2>&1)"
t2=${EPOCHREALTIME/./}
grep -q "merged 4 segments of 201 frames" "$tmp"/jobs/iird-merge-*.log 2>/dev/null ||
    fail "the merge: $(cat "$tmp"/jobs/*.log 2>/dev/null | tail -20)"
[ -s "$tmp/out/orbit.mp4" ] || fail "no video"
n=0
for f in "$tmp"/one/frame_*.png; do cmp -s "$f" "$tmp/out/orbit/${f##*/}" || n=$((n + 1)); done
[ "$n" = 0 ] || fail "$n frames of the Slurm render differ from one process's"
echo "one process: $(((t1 - t0) / 1000)) ms; 4 Slurm array tasks and the merge: $(((t2 - t1) / 1000)) ms"

# ---- 2. a bench's references as 2 array tasks ----
bench=(--anim orbit --frames 0:20 --size 48x36 --ref-spp 8 --ref-every 5 --methods iir,ir --scenes "$src/scenes")
out=$(sbatch --parsable --array=0-1 "$src/deploy/slurm/refs.sbatch" --ref-cache "$tmp/refs" "${bench[@]}" 2>&1) ||
    fail "refs.sbatch: $out"
drain_queue 300 || fail "the reference jobs did not finish"
out=$("$iird" bench --ref-cache "$tmp/refs" "${bench[@]}" --no-charts 2>&1) || fail "bench: $out"
echo "$out" | grep -qE "references: 8 at 8 spp, 8 from the cache" || fail "the bench rendered references again: $out"

if [ $failures -gt 0 ]; then
    echo "$failures failure(s); logs:"
    tail -n 5 "$tmp"/log/*.log "$tmp"/jobs/*.log 2>/dev/null
    exit 1
fi
echo "ok: a one-node Slurm cluster rendered the orbit in 4 segments byte-identical to one process, and a bench's references in 2 tasks"
