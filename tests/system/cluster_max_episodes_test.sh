#!/usr/bin/env bash
# train.max_episodes on the cluster: deploy/local-cluster.sh (a learner, 1 shard, 1 actor, the toy
# task, ports the OS picks) with train.max_updates out of reach must stop by itself once the
# learner has the episode reports it asks for, as `pamdp train` does, well before --duration; the
# last metrics row and episodes.csv say how many it had (the reports in flight at the stop may add
# a few), and a checkpoint is written. Resumed with a larger limit, it goes on to that one.
# Usage: tests/system/cluster_max_episodes_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
test_name=cluster_max_episodes_test
bin=${1:?path to pamdp}
src=${2:?source dir}
# shellcheck source=tests/system/cluster_lib.sh
source "$src/tests/system/cluster_lib.sh"

max_episodes=400
duration=90
run=$work/run
# The episodes column of the run's last metrics row (the learner writes one at its stop).
episodes() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "episodes") c = i } END { if (c) print $c }' \
    "$run/metrics.csv"
}
# Runs the local cluster with ARGS to its own stop; fails if it ran out its --duration instead.
cluster() {
  local start log=$work/logs/local-cluster-$((++runs)).log
  start=$(date +%s)
  PAMDP_BIN=$bin timeout 150 "$src/deploy/local-cluster.sh" --port 0 --actors 1 --shards 1 --duration $duration \
    "$@" >"$log" 2>&1 || fail "local-cluster.sh $* exited with an error"
  took=$(($(date +%s) - start))
  ((took < duration - 10)) || fail "the cluster ran ${took} s: it did not stop at train.max_episodes"
}
runs=0

cluster --config deploy/configs/reach_stop.toml --run-dir "$run" --set train.max_updates=100000000 \
  --set train.max_episodes=$max_episodes --set train.eval_every_updates=0 --set train.log_every_seconds=0.5 \
  --set cluster.heartbeat_ms=200
stopped=$(episodes)
[[ $stopped =~ ^[0-9]+$ ]] && ((stopped >= max_episodes && stopped < max_episodes + 100)) ||
  fail "the learner stopped at '$stopped' episodes, asked for $max_episodes"
rows=$(($(wc -l <"$run/episodes.csv") - 1))
((rows >= max_episodes)) || fail "episodes.csv has $rows rows, fewer than $max_episodes"
[[ -f $run/checkpoint.ckpt ]] || fail "no checkpoint.ckpt at the stop"
first=$took

# Resumed with a larger limit, it counts the episodes before the resume and stops at the new one.
cluster --resume "$run" --set train.max_episodes=$((2 * max_episodes))
resumed=$(episodes)
[[ $resumed =~ ^[0-9]+$ ]] && ((resumed >= 2 * max_episodes && resumed < 2 * max_episodes + 100)) ||
  fail "resumed with train.max_episodes = $((2 * max_episodes)), the learner stopped at '$resumed' episodes"
echo "$test_name: OK (stopped by itself after ${first} s at $stopped episodes, episodes.csv $rows rows;" \
  "resumed, at $resumed)"
