#!/usr/bin/env bash
# Load: many actors (32 by default) on this machine against 2 replay shards and the learner, on
# the HFO task with fast.toml's networks. Every figure is read from the processes' /metrics and
# /proc, never from logs:
#   1. baseline: the learner's updates/s with 2 actors;
#   2. the other actors join (the learner counts all of them);
#   3. over the load window:
#      - the learner's update rate does not collapse (>= --min-rate-ratio of the baseline);
#      - the replay ratio holds: samples per inserted transition stays within 25% of the
#        configured 32 (the shards' rate limiter, not the number of actors, sets it);
#      - backpressure is visible: the actors' pamdp_actor_send_blocked_seconds_total or the
#        shards' pamdp_replay_rate_limiter_insert_wait_seconds_total grow;
#      - nothing grows without bound: transitions sent by actors but not yet inserted by a shard
#        stay within the actors' windows of unacknowledged batches, and the resident
#        memory of the learner and of each shard grows by less than --max-rss-growth-mb after the
#        buffers filled;
#      - every process is still alive.
# Prints the figures as a table and one JSON object as the last line.
# Usage: tests/system/load_test.sh PATH/TO/pamdp SOURCE_DIR [--actors N] [--seconds S]
#          [--min-rate-ratio R] [--max-rss-growth-mb M]
# ctest runs it with 32 actors for 30 s; the soak variant is the same script for minutes:
#   tests/system/load_test.sh build/bin/pamdp . --seconds 300
set -euo pipefail
bin=${1:?path to pamdp}
src=$(cd "${2:?source dir}" && pwd)
shift 2
actors=32
seconds=30
min_rate_ratio=0.5
max_rss_growth_mb=32
while (($#)); do
  case $1 in
    --actors) actors=$2 ;;
    --seconds) seconds=$2 ;;
    --min-rate-ratio) min_rate_ratio=$2 ;;
    --max-rss-growth-mb) max_rss_growth_mb=$2 ;;
    *)
      echo "load_test: unknown option '$1' (valid: --actors N, --seconds S, --min-rate-ratio R, --max-rss-growth-mb M)" >&2
      exit 2
      ;;
  esac
  shift 2
done
((actors >= 2)) || { echo "load_test: --actors must be at least 2" >&2; exit 2; }
test_name=load_test
# shellcheck source=tests/system/cluster_lib.sh
source "$src/tests/system/cluster_lib.sh"

batch=64      # cluster.actor_batch_transitions
window=2      # unacknowledged batches per actor and shard (cluster.actor_batches_in_flight)
ratio=32      # samples per insert: updates_per_step 1 (set here; fast.toml has 0.5) x batch_size 32
common+=(--set train.updates_per_step=1 --set replay.capacity=20000 --set replay.warmup=1000 --set "cluster.actor_batch_transitions=$batch" --set "cluster.actor_batches_in_flight=$window"
  --set train.checkpoint_every_seconds=0)

rss_kb() { awk '$1 == "VmRSS:" { print $2 }' "/proc/$1/status" 2>/dev/null || echo 0; }
# Sum of metric NAME over the URLs given after it.
sum_metric() {
  local name=$1 total=0 v
  shift
  for u in "$@"; do
    v=""
    for _ in 1 2 3 4 5; do  # a loaded machine may miss the 2 s scrape deadline
      v=$(metric "$u" "$name")
      [[ -n $v ]] && break
    done
    [[ -n $v ]] || fail "$u did not answer with $name in 5 tries"
    total=$(awk -v a="$total" -v b="${v:-0}" 'BEGIN { printf "%.6f", a + b }')
  done
  echo "$total"
}
# Every counter the assertions compare, from one pass over the processes.
declare -A c=()
read_counters() {  # $1: prefix (t1 / t2)
  local shard_urls=("${surl[@]}") actor_urls=("${aurl[@]}")
  c[$1_time]=$(date +%s.%N)
  c[$1_updates]=$(updates)
  # Sent before inserted: sent(then) - inserted(now) can only under-state what is in flight now.
  c[$1_sent]=$(sum_metric pamdp_actor_transitions_sent_total "${actor_urls[@]}")
  c[$1_inserted]=$(sum_metric pamdp_replay_transitions_inserted_total "${shard_urls[@]}")
  c[$1_dropped]=$(sum_metric pamdp_replay_sample_replies_dropped_total "${shard_urls[@]}")
  c[$1_sampled]=$(sum_metric pamdp_replay_transitions_sampled_total "${shard_urls[@]}")
  c[$1_limiter_wait]=$(sum_metric pamdp_replay_rate_limiter_insert_wait_seconds_total "${shard_urls[@]}")
  c[$1_blocked]=$(sum_metric pamdp_actor_send_blocked_seconds_total "${actor_urls[@]}")
  c[$1_env_steps]=$(sum_metric pamdp_env_steps_total "${actor_urls[@]}")
}
diff_of() { awk -v a="${c[t1_$1]}" -v b="${c[t2_$1]}" 'BEGIN { printf "%.6f", b - a }'; }
calc() { awk "BEGIN { printf \"%.4f\", $1 }"; }

start_learner learner --config "$src/deploy/configs/fast.toml" --run-dir "$work/run" \
  --set cluster.learner_bind=tcp://127.0.0.1:0 --set cluster.weights_bind=tcp://127.0.0.1:0
start_shard 0
start_shard 1
start_actor 0 actor-0
start_actor 1 actor-1
wait_for 60 "the cluster did not form (shards $(peers replay), actors $(peers actor))" \
  '[[ $(peers replay) == 2 && $(peers actor) == 2 ]]'
wait_for 60 "no updates with 2 actors" 'gt "$(updates)" 500'

# --- 1. baseline with 2 actors ---------------------------------------------------------------
u0=$(updates)
b0=$(date +%s.%N)
sleep 10
u1=$(updates)
b1=$(date +%s.%N)
base_rate=$(calc "($u1 - $u0) / ($b1 - $b0)")
echo "baseline: 2 actors, learner $base_rate updates/s at $(since)"

# --- 2. the other actors join ------------------------------------------------------------------
wait_url=0
for ((i = 2; i < actors; i++)); do start_actor "$i" "actor-$i"; done
wait_url=1
for ((i = 2; i < actors; i++)); do
  log=$work/logs/actor-$i.log
  wait_for 90 "actor $i did not log its metrics URL" '[[ -n $(url_in "$log") ]]'
  aurl[$i]=$(url_in "$log")
done
wait_for 90 "the learner counts $(peers actor) of $actors actors" '[[ $(peers actor) == "$actors" ]]'
echo "$actors actors joined at $(since)"

# --- 3. load window ------------------------------------------------------------------------------
sleep 5  # the new actors' first batches fill the shards
read_counters t1
declare -A rss0=() rss_max=()
for p in learner shard0 shard1; do
  rss0[$p]=$(rss_kb "${pid[$p]}")
  rss_max[$p]=${rss0[$p]}
done
actors_rss0=0
for ((i = 0; i < actors; i++)); do actors_rss0=$((actors_rss0 + $(rss_kb "${pid[actor$i]}"))); done
actors_rss_max=$actors_rss0
end=$(($(date +%s) + seconds))
while (($(date +%s) < end)); do
  sleep 2
  for p in learner shard0 shard1; do
    r=$(rss_kb "${pid[$p]}")
    ((r > rss_max[$p])) && rss_max[$p]=$r
  done
  total=0
  for ((i = 0; i < actors; i++)); do total=$((total + $(rss_kb "${pid[actor$i]}"))); done
  ((total > actors_rss_max)) && actors_rss_max=$total
done
read_counters t2

for p in "${!pid[@]}"; do
  kill -0 "${pid[$p]}" 2>/dev/null || fail "$p exited during the load window"
done
elapsed=$(calc "${c[t2_time]} - ${c[t1_time]}")
load_rate=$(calc "$(diff_of updates) / $elapsed")
rate_ratio=$(calc "$load_rate / $base_rate")
inserted=$(diff_of inserted)
sampled=$(diff_of sampled)
replay_ratio=$(calc "$sampled / ($inserted > 0 ? $inserted : 1)")
in_flight=$(calc "${c[t2_sent]} - ${c[t2_inserted]}")
# Per actor and shard: its window of unacknowledged batches (InsertAck, docs/protocol.md). Before
# the window, the ZeroMQ high water marks and kernel buffers bounded it: 131,072 here.
in_flight_bound=$((actors * 2 * window * batch))
blocked=$(diff_of blocked)
limiter_wait=$(diff_of limiter_wait)
env_rate=$(calc "$(diff_of env_steps) / $elapsed")
growth_mb() { calc "(${rss_max[$1]} - ${rss0[$1]}) / 1024"; }
actors_growth_mb=$(calc "($actors_rss_max - $actors_rss0) / 1024")

printf '%-34s %s\n' "actors" "$actors" "load window (s)" "$elapsed" \
  "learner updates/s (2 actors)" "$base_rate" "learner updates/s ($actors actors)" "$load_rate ($rate_ratio of baseline)" \
  "env steps/s, all actors" "$env_rate" "transitions inserted / sampled" "$inserted / $sampled" \
  "samples per insert (config $ratio)" "$replay_ratio" "sample replies dropped (total)" "${c[t2_dropped]}" \
  "actors blocked on send (s)" "$blocked" "shards holding inserts (s)" "$limiter_wait" \
  "in flight (sent - inserted)" "$in_flight (bound $in_flight_bound)" \
  "RSS growth learner (MB)" "$(growth_mb learner)" "RSS growth shards (MB)" "$(growth_mb shard0) / $(growth_mb shard1)" \
  "RSS growth all actors (MB)" "$actors_growth_mb (total $((actors_rss_max / 1024)) MB)"

awk -v r="$rate_ratio" -v m="$min_rate_ratio" 'BEGIN { exit !(r >= m) }' ||
  fail "the learner's update rate collapsed: $load_rate/s with $actors actors, $base_rate/s with 2 ($rate_ratio < $min_rate_ratio)"
awk -v r="$replay_ratio" -v t="$ratio" 'BEGIN { exit !(r >= 0.75 * t && r <= 1.25 * t) }' ||
  fail "samples per insert was $replay_ratio over the window, the config says $ratio (inserted $inserted, sampled $sampled)"
awk -v b="$blocked" -v w="$limiter_wait" 'BEGIN { exit !(b + w > 0) }' ||
  fail "no backpressure visible: actors blocked $blocked s, shards held inserts $limiter_wait s"
awk -v f="$in_flight" -v b="$in_flight_bound" 'BEGIN { exit !(f <= b) }' ||
  fail "$in_flight transitions sent but not yet inserted: more than the actors' windows allow ($in_flight_bound)"
for p in learner shard0 shard1; do
  awk -v g="$(growth_mb "$p")" -v m="$max_rss_growth_mb" 'BEGIN { exit !(g <= m) }' ||
    fail "$p grew by $(growth_mb "$p") MB of resident memory in ${elapsed} s (limit $max_rss_growth_mb MB)"
done
awk -v g="$actors_growth_mb" -v m="$max_rss_growth_mb" 'BEGIN { exit !(g <= m) }' ||
  fail "the actors together grew by $actors_growth_mb MB of resident memory (limit $max_rss_growth_mb MB)"

echo "load_test: OK: $actors actors for $elapsed s, learner at $rate_ratio of its 2-actor rate, replay ratio $replay_ratio, in flight $in_flight <= $in_flight_bound, in $(since)"
printf '{"actors":%d,"seconds":%s,"base_updates_per_s":%s,"load_updates_per_s":%s,"rate_ratio":%s,"env_steps_per_s":%s,"inserted":%s,"sampled":%s,"samples_per_insert":%s,"sample_replies_dropped":%s,"actor_blocked_s":%s,"limiter_wait_s":%s,"in_flight":%s,"in_flight_bound":%d,"rss_growth_mb":{"learner":%s,"shard0":%s,"shard1":%s,"actors":%s}}\n' \
  "$actors" "$elapsed" "$base_rate" "$load_rate" "$rate_ratio" "$env_rate" "$inserted" "$sampled" "$replay_ratio" \
  "${c[t2_dropped]}" "$blocked" "$limiter_wait" "$in_flight" "$in_flight_bound" \
  "$(growth_mb learner)" "$(growth_mb shard0)" "$(growth_mb shard1)" "$actors_growth_mb"
