#!/usr/bin/env bash
# train.max_episodes on the cluster: deploy/local-cluster.sh (a learner, 1 shard, 1 actor, the toy
# task, ports the OS picks) with train.max_updates out of reach must stop by itself once the
# learner has the episode reports it asks for, as `pamdp train` does, well before --duration; the
# learner's last line and the run's episodes.csv say how many it had (the reports in flight at
# the stop may add a few); resumed with a larger limit, it goes on to that one.
# Usage: tests/cluster_max_episodes_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
bin=${1:?path to pamdp}
src=${2:?source dir}
work=$(mktemp -d /tmp/pamdp-max-episodes.XXXXXX)
keep=0
cleanup() { if ((keep)); then echo "kept $work"; else rm -rf "$work"; fi; }
trap cleanup EXIT
fail() {
  echo "cluster_max_episodes_test: FAIL: $*" >&2
  for f in "$work"/out.log "$work"/run/logs/*.log; do echo "--- $f"; tail -n 15 "$f"; done >&2
  keep=1
  exit 1
}
max_episodes=400
duration=90
start=$(date +%s)
PAMDP_BIN=$bin timeout 150 "$src/deploy/local-cluster.sh" --port 0 --actors 1 --shards 1 \
  --config deploy/configs/reach_stop.toml --run-dir "$work/run" --duration $duration \
  --set train.max_updates=100000000 --set train.max_episodes=$max_episodes --set train.eval_every_updates=0 \
  --set train.log_every_seconds=0.5 --set cluster.heartbeat_ms=200 >"$work/out.log" 2>&1 ||
  fail "local-cluster.sh exited with an error"
took=$(($(date +%s) - start))
((took < duration - 10)) || fail "the cluster ran ${took} s: it did not stop at train.max_episodes = $max_episodes"
line=$(grep "learner stopped:" "$work/run/logs/learner.log" | tail -n 1 || true)
[[ -n $line ]] || fail "the learner did not log its stop"
stopped=$(sed -E 's/.* ([0-9]+) episodes;.*/\1/' <<<"$line")
[[ $stopped =~ ^[0-9]+$ ]] || fail "no episode count in '$line'"
((stopped >= max_episodes && stopped < max_episodes + 100)) ||
  fail "the learner stopped at $stopped episodes, asked for $max_episodes ($line)"
rows=$(($(wc -l <"$work/run/episodes.csv") - 1))
((rows >= max_episodes)) || fail "episodes.csv has $rows rows, fewer than $max_episodes"
[[ -f $work/run/checkpoint.ckpt ]] || fail "no checkpoint.ckpt at the stop"
# Resumed with a larger limit, it counts the episodes before the resume and stops at the new one.
PAMDP_BIN=$bin timeout 150 "$src/deploy/local-cluster.sh" --port 0 --actors 1 --shards 1 --resume "$work/run" \
  --duration $duration --set train.max_episodes=$((2 * max_episodes)) >"$work/out-resumed.log" 2>&1 ||
  fail "local-cluster.sh --resume exited with an error"
line=$(grep "learner stopped:" "$work/run/logs/learner.log" | tail -n 1 || true)
resumed=$(sed -E 's/.* ([0-9]+) episodes;.*/\1/' <<<"$line")
[[ $resumed =~ ^[0-9]+$ ]] && ((resumed >= 2 * max_episodes && resumed < 2 * max_episodes + 100)) ||
  fail "resumed with train.max_episodes = $((2 * max_episodes)), the learner stopped at '$resumed' ($line)"
echo "cluster_max_episodes_test: OK (stopped by itself after ${took} s at $stopped episodes, episodes.csv $rows rows;" \
  "resumed, at $resumed)"
