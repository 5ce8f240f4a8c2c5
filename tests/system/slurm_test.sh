#!/usr/bin/env bash
# deploy/slurm/pamdp.sbatch on a real two-node Slurm 22.05 (Debian's slurmctld, slurmd,
# slurm-client and munge; installed with apt-get when missing), both nodes on this host over
# loopback: n1 and n2 are two slurmd with their own ports, spool and logs. Everything the test
# starts is its own: a munged on its own socket, a slurm.conf in the work directory (SLURM_CONF),
# free ports; the daemons are stopped at the end, whatever happens.
#   1. sbatch --nodes=2 --ntasks-per-node=4 with SHARDS=2: the learner and 2 shards on n1, 5 actors
#      (1 on n1, 4 on n2), CURVE with keys the job makes itself in the shared directory. The
#      learner's /metrics must count 2 shards and 5 actors while its updates grow, metrics.csv
#      must log actors_joined = 5, and every process must run on the node the layout says
#      (SLURMD_NODENAME in its environment).
#   2. scancel: the job ends, no process of it is left, the checkpoint and snapshots are written.
#   3. a second sbatch with the same RUN_DIR resumes it: the learner starts at the checkpoint's
#      updates, every shard restores its snapshot, 5 actors join again, and the job ends by itself
#      (train.max_seconds) with exit code 0 and no process left.
# Skips (77) when Slurm is missing and cannot be installed, or without root.
# Usage: tests/system/slurm_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
bin=$(readlink -f "${1:?path to pamdp}")
src=$(cd "${2:?source dir}" && pwd)
test_name=slurm_test

skip() {
  echo "$test_name: SKIP: $*"
  exit 77
}
[[ $(id -u) == 0 ]] || skip "needs root to run slurmd and munged"
need=()
for tool in slurmctld:slurmctld slurmd:slurmd sbatch:slurm-client munged:munge curl:curl flatc:flatbuffers-compiler; do
  command -v "${tool%%:*}" >/dev/null || [[ -x /usr/sbin/${tool%%:*} ]] || need+=("${tool#*:}")
done
if ((${#need[@]})); then
  echo "$test_name: installing ${need[*]}"
  export DEBIAN_FRONTEND=noninteractive
  { apt-get update -qq && apt-get install -y -qq --no-install-recommends "${need[@]}"; } >/dev/null 2>&1 ||
    skip "cannot install ${need[*]} with apt-get"
fi
export PATH=$PATH:/usr/sbin

work=$(mktemp -d "/tmp/pamdp-$test_name.XXXXXX")
chmod 755 "$work"  # munged (user munge) must reach its socket directory
daemons=()
jobs=()
cleanup() {
  local status=$? j
  for j in "${jobs[@]}"; do
    scancel "$j" 2>/dev/null || true
    for _ in $(seq 60); do [[ -z $(job_pids "$j") ]] && break; sleep 0.5; done
  done
  for p in "${daemons[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  for p in "${daemons[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$p" 2>/dev/null || true
  done
  if [[ ${keep:-0} == 1 ]]; then echo "kept $work"; else rm -rf "$work"; fi
  exit "$status"
}
trap cleanup EXIT
fail() {
  echo "$test_name: FAIL: $*" >&2
  for f in "$work"/job-*.out "$work"/run/logs/*.log "$work"/log/*.log; do
    [[ -f $f ]] && { echo "--- $f"; tail -n 15 "$f"; }
  done >&2
  keep=1
  exit 1
}
t0=$(date +%s.%N)
since() { awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1fs", b - a }'; }
wait_for() {
  local seconds=$1 what=$2
  shift 2
  local deadline=$(($(date +%s) + seconds))
  until eval "$*"; do
    (($(date +%s) < deadline)) || fail "$(eval "echo \"$what\"") (not within ${seconds}s)"
    sleep 0.5
  done
}
gt() { awk -v a="${1:-}" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 > b + 0) }'; }
ge() { awk -v a="${1:-}" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 >= b + 0) }'; }

# Five consecutive free TCP ports (slurmctld, slurmd n1 and n2, the learner's join and weights),
# below the kernel's ephemeral range: the replay shards and every other test bind port 0 and
# get theirs from that range, and one took the learner's port between this check and its bind
# while ctest ran tests beside this one.
port_free() { ! ss -Htan "sport = :$1" | grep -q .; }
read -r eph_low _ </proc/sys/net/ipv4/ip_local_port_range 2>/dev/null || eph_low=32768
top=$((eph_low > 12000 ? eph_low - 10 : 32000))
base=""
for _ in $(seq 50); do
  b=$((10000 + RANDOM % (top - 10000)))
  if port_free "$b" && port_free $((b + 1)) && port_free $((b + 2)) && port_free $((b + 3)) && port_free $((b + 4)); then
    base=$b
    break
  fi
done
[[ -n $base ]] || fail "no five free ports found"

# --- munge and a two-node Slurm on loopback ---------------------------------------------------
[[ -f /etc/munge/munge.key ]] || skip "no /etc/munge/munge.key (the munge package makes it)"
mkdir -p "$work/munge" "$work/state" "$work/spool" "$work/log"
chown munge:munge "$work/munge"
runuser -u munge -- munged --socket="$work/munge/socket" --pid-file="$work/munge/munged.pid" \
  --log-file="$work/munge/munged.log" --seed-file="$work/munge/seed" ||
  fail "munged did not start: $(tail -n 3 "$work/munge/munged.log")"
daemons+=("$(cat "$work/munge/munged.pid")")

cat >"$work/slurm.conf" <<EOF
ClusterName=pamdptest
SlurmctldHost=$(hostname -s)(127.0.0.1)
SlurmctldPort=$base
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool/%n
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd-%n.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd-%n.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MailProg=/bin/true
KillWait=10
InactiveLimit=0
NodeName=n[1-2] NodeHostname=localhost NodeAddr=127.0.0.1 Port=[$((base + 1))-$((base + 2))] CPUs=4 State=UNKNOWN
PartitionName=test Nodes=n[1-2] Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm.conf
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
wait_for 10 "slurmctld wrote no pid file" "[[ -s $work/slurmctld.pid ]]"
daemons+=("$(cat "$work/slurmctld.pid")")
for n in n1 n2; do
  slurmd -f "$SLURM_CONF" -N "$n" || fail "slurmd -N $n did not start"
  wait_for 10 "slurmd -N $n wrote no pid file" "[[ -s $work/slurmd-$n.pid ]]"
  daemons+=("$(cat "$work/slurmd-$n.pid")")
done
wait_for 30 'the two nodes did not come up: $(echo $(sinfo -h -o %N:%t 2>&1))' \
  '[[ $(sinfo -h -N -t idle -o %N 2>/dev/null | sort -u | wc -l) == 2 ]]'
echo "slurm up at $(since): $(sinfo -h -N -o '%N:%t' | sort -u | tr '\n' ' ')(ports $base-$((base + 2)))"

# --- the job, as a user submits it from the repository root ----------------------------------
export PAMDP_BIN=$bin RUN_DIR=$work/run KEYS=$work/keys SHARDS=2 PORT=$((base + 3))
quick=(--set replay.warmup=500 --set train.eval_every_updates=0 --set train.log_every_seconds=0.5
  --set train.checkpoint_every_seconds=1 --set cluster.heartbeat_ms=200 --set cluster.peer_timeout_ms=1500)
submit() {
  (cd "$src" && sbatch --parsable --nodes=2 --ntasks-per-node=4 --output="$work/job-%j.out" \
    deploy/slurm/pamdp.sbatch "$@")
}
state() { scontrol show job "$1" 2>/dev/null | grep -o 'JobState=[A-Z]*' | cut -d= -f2; }
# PIDs of the processes this job started (SLURM_JOB_ID in their environment), slurmstepd included.
job_pids() {
  local p
  for p in /proc/[0-9]*; do
    tr '\0' '\n' 2>/dev/null <"$p/environ" | grep -qx "SLURM_JOB_ID=$1" && echo "${p#/proc/}"
  done
  pgrep -f "slurmstepd: \[$1\." || true
}
# Where each pamdp process of the job runs: "learner n1", "replay n1", "actor n2", … sorted.
layout() {
  local p role node
  for p in $(job_pids "$1"); do
    role=$(tr '\0' ' ' 2>/dev/null <"/proc/$p/cmdline" | awk -v bin="$bin" '$1 == bin { print $2 }')
    [[ -n $role ]] || continue
    node=$(tr '\0' '\n' 2>/dev/null <"/proc/$p/environ" | grep '^SLURMD_NODENAME=' | cut -d= -f2)
    echo "$role $node"
  done | sort | uniq -c | awk '{ printf "%s:%s=%s ", $2, $3, $1 }'
}
# The metrics URL of the process with this role (pamdp_process_info) among metrics_urls.txt.
url_of() {
  local u
  while read -r u; do
    curl -sf --max-time 2 "$u" 2>/dev/null | grep -q "^pamdp_process_info{role=\"$1\"" && echo "$u"
  done <"$RUN_DIR/metrics_urls.txt" 2>/dev/null || true
}
metric() {
  curl -sf --max-time 2 "$1" 2>/dev/null |
    awk -v name="$2" -v labels="${3:-}" '$1 == name || (index($1, name "{") == 1 && index($1, labels) > 0) { print $2; exit }' || true
}
# Column NAME of metrics.csv's last row.
csv_last() { awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i; next } { v = $c } END { print v }' "$RUN_DIR/metrics.csv"; }
expected_layout="actor:n1=1 actor:n2=4 learner:n1=1 replay:n1=2 "

job1=$(submit "${quick[@]}")
jobs+=("$job1")
wait_for 60 'job $job1 is $(state "$job1"), its learner listed no metrics URL' '[[ -s $RUN_DIR/metrics_urls.txt ]]'
lurl=""
wait_for 30 "no learner among the metrics URLs" 'lurl=$(url_of learner | head -n 1); [[ -n $lurl ]]'
actors() { metric "$lurl" pamdp_learner_peers_connected 'role="actor"'; }
shards() { metric "$lurl" pamdp_learner_peers_connected 'role="replay"'; }
wait_for 60 'the learner counts $(shards) shards and $(actors) actors, not 2 and 5' '[[ $(shards) == 2 && $(actors) == 5 ]]'
u0=$(metric "$lurl" pamdp_updates_total)
wait_for 60 "the learner's updates stuck at \$(metric \"\$lurl\" pamdp_updates_total) with every actor joined" \
  "gt \"\$(metric \"\$lurl\" pamdp_updates_total)\" $((${u0%.*} + 2000))"
wait_for 10 'metrics.csv logs actors_joined $(csv_last actors_joined), not 5' '[[ $(csv_last actors_joined) == 5 ]]'
seen=$(layout "$job1")
[[ $seen == "$expected_layout" ]] || fail "processes of job $job1 run as '$seen', not '$expected_layout'"
echo "job $job1 at $(since): updates $(metric "$lurl" pamdp_updates_total), 2 shards and 5 actors joined; $seen"

# --- scancel: nothing left, a resumable run directory ------------------------------------------
scancel "$job1"
wait_for 40 'job $job1 still $(state "$job1") after scancel' '[[ $(state "$job1") == CANCELLED ]]'
wait_for 40 'processes of job $job1 left after scancel: $(echo $(job_pids "$job1"))' '[[ -z $(job_pids "$job1") ]]'
for f in checkpoint.ckpt shard-0.replay shard-1.replay; do
  [[ -s $RUN_DIR/$f ]] || fail "scancel left no $f in the run directory"
done
cp "$RUN_DIR/checkpoint.ckpt" "$work/cancelled.ckpt"
(cd "$work" && flatc --json --strict-json --raw-binary "$src/schemas/checkpoint.fbs" -- cancelled.ckpt)
ck_updates=$(grep -o '"updates": *[0-9]*' "$work/cancelled.json" | grep -o '[0-9]*$' || echo 0)
((ck_updates > 0)) || fail "the checkpoint left by scancel holds no updates"
echo "scancel at $(since): job $job1 cancelled, no process left, checkpoint at $ck_updates updates"

# --- a second sbatch resumes the run directory, then ends by itself ---------------------------
# Ends by the learner's own clock (train.max_seconds counts from its start), not by updates, so
# that the checks below see it running however loaded the machine is.
job2=$(submit --set train.max_seconds=40)
jobs+=("$job2")
wait_for 60 'job $job2 is $(state "$job2"), its learner did not answer' \
  'lurl=$(url_of learner | head -n 1); [[ -n $lurl ]] && gt "$(metric "$lurl" pamdp_updates_total)" 0'
first=$(metric "$lurl" pamdp_updates_total)
ge "$first" "$ck_updates" || fail "the resumed learner is at $first updates, the checkpoint had $ck_updates"
wait_for 30 "the resumed shards did not both list their metrics URLs" '[[ $(url_of replay | wc -l) == 2 ]]'
# A shard lists its URL when it asks to join and restores its snapshot when the map comes, and a
# scrape on a loaded machine can time out: read until both counts are in (once was flaky).
restored_counts() {
  local u r=""
  for u in $(url_of replay); do r+="$(metric "$u" pamdp_replay_restored_transitions) "; done
  echo "$r"
}
wait_for 20 "the resumed shards restored '\$(restored_counts)' transitions (want two counts > 0)" \
  'restored=$(restored_counts); [[ $restored =~ ^[1-9][0-9]*\ [1-9][0-9]*\ $ ]]'
wait_for 60 'the resumed learner counts $(shards) shards and $(actors) actors, not 2 and 5' '[[ $(shards) == 2 && $(actors) == 5 ]]'
seen=$(layout "$job2")
[[ $seen == "$expected_layout" ]] || fail "processes of job $job2 run as '$seen', not '$expected_layout'"
wait_for 90 'job $job2 is $(state "$job2") at $(csv_last updates) updates' '[[ $(state "$job2") == COMPLETED ]]'
exit_code=$(scontrol show job "$job2" | grep -o ' ExitCode=[0-9:]*' | cut -d= -f2)
[[ $exit_code == 0:0 ]] || fail "job $job2 ended with exit code $exit_code"
gt "$(csv_last updates)" $((ck_updates + 1000)) || fail "metrics.csv ends at $(csv_last updates) updates, hardly past the checkpoint's $ck_updates"
wait_for 20 'processes of job $job2 left after it ended: $(echo $(job_pids "$job2"))' '[[ -z $(job_pids "$job2") ]]'
echo "job $job2 at $(since): resumed at $first updates (checkpoint $ck_updates), shards restored ${restored% }" \
  "transitions, 5 actors joined, ended by itself at $(csv_last updates) updates with exit code 0; $seen"
echo "$test_name: PASS in $(since)"
