#!/usr/bin/env bash
# deploy/local-cluster.sh --curve (issue 33): the local cluster with fresh keys from pamdp keygen
# in the run directory, CURVE on every socket. A learner, 1 shard and 1 actor on the toy task, on
# ports the OS chooses (--port 0), for 12 s. Asserts that the keys were made
# private, the saved config has CURVE on, updates happened from the shard's samples, the actor
# joined and inserted, and an actor without the keys was refused and counted on the learner's /metrics.
# Usage: tests/local_cluster_curve_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
bin=${1:?path to pamdp}
src=${2:?source dir}
work=$(mktemp -d /tmp/pamdp-local-curve.XXXXXX)
keep=0
cleanup() { if ((keep)); then echo "kept $work"; else rm -rf "$work"; fi; }
trap cleanup EXIT
fail() {
  echo "local_cluster_curve_test: FAIL: $*" >&2
  for f in "$work"/out.log "$work"/run/logs/*.log; do echo "--- $f"; tail -n 15 "$f"; done >&2
  keep=1
  exit 1
}
min_updates=1000
PAMDP_BIN=$bin timeout 120 "$src/deploy/local-cluster.sh" --curve --port 0 --actors 1 --shards 1 \
  --config deploy/configs/reach_stop.toml --run-dir "$work/run" --duration 12 \
  --set train.max_updates=100000000 --set train.eval_every_updates=0 --set train.log_every_seconds=0.5 \
  --set cluster.heartbeat_ms=200 >"$work/out.log" 2>&1 &
script=$!

# While it runs: an actor without keys must not join (the learner refuses its handshake).
join=""
for _ in $(seq 200); do
  join=$(grep -o "learner: *tcp://127\.0\.0\.1:[0-9]*" "$work/out.log" | head -n 1 | grep -o 'tcp://.*' || true)
  [[ -n $join ]] && break
  sleep 0.1
done
[[ -n $join ]] || fail "local-cluster.sh did not print the learner's endpoint"
grep -q "CURVE on every socket" "$work/out.log" || fail "local-cluster.sh did not say CURVE is on"
"$bin" actor --join "$join" --join-timeout 3 >"$work/run/logs/intruder.log" 2>&1 && fail "an actor without keys joined"
lurl=$(grep -o 'http://127\.0\.0\.1:[0-9]*/metrics' "$work/run/logs/learner.log" | head -n 1 || true)
[[ -n $lurl ]] || fail "the learner did not log its metrics URL"
refused=$(curl -sf --max-time 2 "$lurl" | awk '$1 == "pamdp_connections_refused_total" { print $2 }' || true)
[[ $refused =~ ^[0-9]+$ ]] && ((refused >= 1)) || fail "the learner counted no refused connection (got '$refused')"

wait "$script" || fail "local-cluster.sh exited with an error"
# The learner's final line reaches the terminal, not only its log, once (issue 81).
n_final=$(grep -c "^learner stopped: [0-9]* updates" "$work/out.log" || true)
[[ $n_final == 1 ]] || fail "local-cluster.sh printed the learner's final line $n_final times, not once"
grep -q "HFO takes tens of minutes" "$work/out.log" && fail "local-cluster.sh said HFO takes minutes on the toy task"
for f in server.keys client.keys; do
  [[ -f $work/run/keys/$f ]] || fail "no $f in the run directory's keys"
  mode=$(stat -c %a "$work/run/keys/$f")
  [[ $mode == 600 ]] || fail "$f has mode $mode, expected 600"
done
grep -q '^curve = true' "$work/run/config.toml" || fail "the run's config.toml does not have curve = true"
metrics=$work/run/metrics.csv
[[ -f $metrics ]] || fail "no metrics.csv"
column() {
  awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i } END { if (c) print $c }' "$metrics"
}
updates=$(column updates)
shards=$(column shards)
actors=$(column actors_joined)
echo "learner: updates=$updates shards=$shards actors=$actors; refused $refused connection(s) of the keyless actor"
((updates >= min_updates)) || fail "updates $updates < $min_updates"
((shards == 1)) || fail "expected 1 shard in the map, got $shards"
((actors == 1)) || fail "expected exactly 1 actor (the one with keys), got $actors"
line=$(grep "transitions inserted" "$work/run/logs/shard-0.log" | tail -n 1)
inserted=$(sed -E 's/.* ([0-9]+) transitions inserted.*/\1/' <<<"$line")
[[ $inserted =~ ^[0-9]+$ ]] && ((inserted > 0)) || fail "the shard inserted nothing ($line)"
echo "local_cluster_curve_test: OK (shard inserted $inserted transitions)"
