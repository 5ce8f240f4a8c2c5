#!/usr/bin/env bash
# Learner updates/s while fed over the network, next to the same update fed in process
# (BM_DdpgUpdate/<batch> of pamdp-bench): the issue's goal is >= 90 % of in-process.
#
#   bench/learner_network.sh [--config FILE] [--seconds S] [--shards K] [--set key=value ...]
#
# Starts K replay shards and the learner on loopback, lets one actor fill the shards past the
# warm-up, stops the actor, and then measures the learner alone for S seconds (default 20)
# with the rate limiter opened, so it updates as fast as it can sample. Run it on an idle
# machine: the learner takes one core and the shards share the other.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

config=deploy/configs/paper.toml
seconds=20
shards=1
sets=()
die() { echo "learner_network: $*" >&2; exit 2; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --config) config=$2; shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --shards) shards=$2; shift 2 ;;
    --set) sets+=(--set "$2"); shift 2 ;;
    -h|--help) sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
[[ -f $config ]] || die "no config file '$config'"
bin=${PAMDP_BIN:-build/bin/pamdp}
bench=${PAMDP_BENCH:-build/bin/pamdp-bench}
[[ -x $bin && -x $bench ]] || die "build first: tests/run.sh (needs $bin and $bench)"

work=$(mktemp -d /tmp/pamdp-learner-net.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

common=(--set replay.warmup=2000 --set cluster.samples_per_insert=1000000 --set train.eval_every_updates=0
  --set train.log_every_seconds=1 --set "replay.shards=$shards" "${sets[@]}")
"$bin" learner --config "$config" --run-dir "$work/run" --set cluster.learner_bind=tcp://127.0.0.1:0 \
  --set cluster.weights_bind=tcp://127.0.0.1:0 "${common[@]}" >"$work/learner.log" 2>&1 &
pids+=($!)
join=""
for _ in $(seq 100); do
  join=$(grep -o "join: *tcp://127.0.0.1:[0-9]*" "$work/learner.log" | head -n1 | grep -o 'tcp://.*' || true)
  [[ -n $join ]] && break
  sleep 0.1
done
[[ -n $join ]] || die "the learner did not start: $(tail -n 5 "$work/learner.log")"
for ((i = 0; i < shards; i++)); do
  "$bin" replay --join "$join" --insert-bind tcp://127.0.0.1:0 --sample-bind tcp://127.0.0.1:0 \
    >"$work/shard-$i.log" 2>&1 &
  pids+=($!)
done
"$bin" actor --join "$join" --seed 7 >"$work/actor.log" 2>&1 &
actor=$!

metrics=$work/run/metrics.csv
column() {
  awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i } END { if (c) print $c }' "$metrics"
}
for _ in $(seq 600); do
  [[ -f $metrics && $(column updates) -gt 500 ]] 2>/dev/null && break
  sleep 0.1
done
[[ -f $metrics && $(column updates) -gt 500 ]] || die "no updates after 60 s: $(tail -n 3 "$work/learner.log")"
kill -TERM "$actor" 2>/dev/null || true
wait "$actor" 2>/dev/null || true
sleep 3
u0=$(column updates)
t0=$(column wall_seconds)
sleep "$seconds"
u1=$(column updates)
t1=$(column wall_seconds)
net=$(awk -v a="$u0" -v b="$u1" -v s="$t0" -v e="$t1" 'BEGIN { printf "%.1f", (b - a) / (e - s) }')

batch=$(awk -F= '/^batch_size/ { gsub(/ /, "", $2); print $2 }' "$work/run/config.toml")
# The cluster stops before the in-process measurement, which needs the core to itself.
for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
wait 2>/dev/null || true
pids=()
inproc=$("$bench" --benchmark_filter="^BM_DdpgUpdate/${batch}\$" --benchmark_min_time=5 --benchmark_format=csv 2>/dev/null |
  awk -F, '/^name,/ { for (i = 1; i <= NF; i++) if ($i == "items_per_second") c = i; next }
    /BM_DdpgUpdate/ && c { print $c }' || true)
[[ -n $inproc ]] || inproc=0
ratio=$(awk -v n="$net" -v p="$inproc" 'BEGIN { if (p > 0) printf "%.0f %%", 100 * n / p; else print "?" }')
printf '\n| config | batch | shards | network-fed updates/s | in-process (BM_DdpgUpdate/%s) | ratio |\n' "$batch"
printf '| --- | --- | --- | --- | --- | --- |\n'
printf '| %s | %s | %s | %s | %.1f | %s |\n' "$(basename "$config" .toml)" "$batch" "$shards" "$net" "$inproc" "$ratio"
