#!/usr/bin/env bash
# Live metrics of a running cluster: a learner, one replay shard and two actors on the toy
# ReachStop task, as real processes on loopback. Each serves /metrics on a port of its own choice
# and the learner lists them in the run directory's metrics_urls.txt.
#   prometheus: a real Prometheus (/usr/bin/prometheus) scrapes every listed process each second;
#               the test asks Prometheus' HTTP API that every target is up and that counters grew.
#               Exits 77 (ctest: skipped) with a message when prometheus is not installed.
#   monitor:    `pamdp monitor --join ... --once --json` and `pamdp monitor URL... --once` against
#               the cluster, checking the fields they report, and that a frame over the
#               learner's size limit (tests/zmtp_send.py) shows, counted against its peer.
# Usage: tests/metrics_cluster_test.sh PATH/TO/pamdp SOURCE_DIR prometheus|monitor
set -euo pipefail
bin=${1:?path to pamdp}
src=${2:?source dir}
mode=${3:?prometheus or monitor}
prometheus=${PROMETHEUS:-$(command -v prometheus || true)}
if [[ $mode == prometheus && ! -x $prometheus ]]; then
  echo "metrics_cluster_test: SKIPPED: prometheus is not installed (Debian package prometheus; deploy/install-deps.sh)"
  exit 77
fi
work=$(mktemp -d /tmp/pamdp-metrics-test.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [[ ${keep:-0} == 1 ]]; then echo "kept $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT
fail() {
  echo "metrics_cluster_test $mode: FAIL: $*" >&2
  for f in "$work"/logs/*.log; do echo "--- $f"; tail -n 15 "$f"; done >&2
  keep=1
  exit 1
}
mkdir -p "$work/logs"

"$bin" learner --config "$src/deploy/configs/reach_stop.toml" --run-dir "$work/run" \
  --set cluster.learner_bind=tcp://127.0.0.1:0 --set cluster.weights_bind=tcp://127.0.0.1:0 \
  --set replay.shards=1 --set train.max_updates=100000000 --set train.eval_every_updates=0 \
  --metrics-bind 127.0.0.1 --metrics-port 0 >"$work/logs/learner.log" 2>&1 &
pids+=($!)
join=""
for _ in $(seq 100); do
  join=$(grep -o "join: *tcp://127.0.0.1:[0-9]*" "$work/logs/learner.log" | head -n1 | grep -o 'tcp://.*' || true)
  [[ -n $join ]] && break
  sleep 0.1
done
[[ -n $join ]] || fail "the learner did not report its join endpoint"
"$bin" replay --join "$join" --insert-bind tcp://127.0.0.1:0 --sample-bind tcp://127.0.0.1:0 >"$work/logs/shard.log" 2>&1 &
pids+=($!)
for i in 0 1; do
  "$bin" actor --join "$join" --seed $((20 + i)) >"$work/logs/actor-$i.log" 2>&1 &
  pids+=($!)
done

# The learner lists itself, the shard and both actors once they have joined.
urls_file=$work/run/metrics_urls.txt
for _ in $(seq 150); do
  [[ -f $urls_file && $(wc -l <"$urls_file") -ge 4 ]] && break
  sleep 0.1
done
[[ -f $urls_file && $(wc -l <"$urls_file") -eq 4 ]] || fail "metrics_urls.txt does not list 4 processes: $(cat "$urls_file" 2>/dev/null)"
mapfile -t urls <"$urls_file"
echo "metrics URLs: ${urls[*]}"
for u in "${urls[@]}"; do
  # The body first: `curl | grep -q` fails under pipefail when grep exits before curl's last write.
  body=$(curl -sf --max-time 2 "$u") || fail "$u does not answer"
  grep -q '^pamdp_process_info{role="' <<<"$body" || fail "$u does not serve pamdp metrics"
done

if [[ $mode == monitor ]]; then
  # A top-level number (or null) of the JSON line: the first "key":number match.
  field() { grep -o "\"$1\":\(-\?[0-9][0-9.eE+-]*\|null\)" <<<"$json" | head -n1 | cut -d: -f2; }
  # Until the cluster is past warm-up (on a loaded machine the first interval may see no steps).
  for _ in $(seq 20); do
    sleep 1
    json=$("$bin" monitor --join "$join" --once --json | tail -n 1)
    awk -v s="$(field env_steps_per_s)" -v u="$(field updates)" 'BEGIN { exit !(s > 0 && u > 0) }' && break
  done
  echo "monitor --json: ${json:0:600}..."
  [[ $(field targets) == 4 && $(field up) == 4 ]] || fail "monitor sees $(field up)/$(field targets) targets up"
  [[ $(field actors_alive) == 2 ]] || fail "monitor counts $(field actors_alive) actors alive"
  grep -q '"roles":{"actor":2,"learner":1,"replay":1}' <<<"$json" || fail "monitor roles wrong"
  awk -v v="$(field env_steps_per_s)" 'BEGIN { exit !(v > 0) }' || fail "no env steps/s: $(field env_steps_per_s)"
  awk -v v="$(field replay_capacity)" 'BEGIN { exit !(v == 50000) }' || fail "replay capacity $(field replay_capacity)"
  awk -v v="$(field updates)" 'BEGIN { exit !(v > 0) }' || fail "no updates: $(field updates)"
  for f in inserts_per_s samples_per_s updates_per_s replay_fill episodes goal_rate_100 mean_return_100 critic_loss \
    q_mean epsilon weights_version weights_age_max; do
    [[ -n $(field $f) && $(field $f) != null ]] || fail "monitor field $f is missing or null"
  done
  text=$("$bin" monitor --once --interval 0.5 "${urls[@]}")
  echo "$text"
  grep -q "4/4 targets up" <<<"$text" || fail "monitor URL... does not show 4 targets up"
  if grep -q $'\x1b' <<<"$text"; then fail "monitor --once printed escape codes"; fi
  grep -q '"oversized_frames":\[\]' <<<"$json" || fail "monitor counts oversized frames before any was sent"

  # A frame over the learner's join-socket limit (1 MiB; ZeroMQ's own cap is twice that), from a
  # connection that never joined: refused, counted against "unknown", shown by the monitor.
  hostport=${join#tcp://}
  /usr/bin/python3 "$src/tests/zmtp_send.py" "${hostport%:*}" "${hostport##*:}" $((3 << 19)) ||
    fail "could not send the oversized frame"
  for _ in $(seq 20); do
    json=$("$bin" monitor --join "$join" --once --json | tail -n 1)
    grep -q '"oversized_frames":\[{"frames":1[.0]*,"observer":"learner:[^"]*","peer":"unknown"}\]' <<<"$json" && break
    sleep 0.5
  done
  grep -q '"peer":"unknown"' <<<"$json" || fail "monitor --json does not list the oversized frame: ${json:0:800}"
  text=$("$bin" monitor --once --interval 0.5 "${urls[@]}")
  grep -q "frames refused for size: unknown -> learner 1" <<<"$text" || fail "monitor does not show the oversized frame"
  echo "metrics_cluster_test monitor: OK"
  exit 0
fi

# A free port for Prometheus' web API.
port=""
for _ in $(seq 50); do
  p=$((20000 + RANDOM % 40000))
  if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then port=$p; break; fi
done
[[ -n $port ]] || fail "no free port for prometheus"
{
  echo "global:"
  echo "  scrape_interval: 1s"
  echo "  scrape_timeout: 1s"
  echo "scrape_configs:"
  echo "  - job_name: pamdp"
  echo "    static_configs:"
  echo "      - targets:"
  for u in "${urls[@]}"; do
    hostport=${u#http://}
    echo "          - '${hostport%%/*}'"
  done
} >"$work/prometheus.yml"
"$prometheus" --config.file="$work/prometheus.yml" --storage.tsdb.path="$work/tsdb" \
  --web.listen-address="127.0.0.1:$port" --log.level=warn >"$work/logs/prometheus.log" 2>&1 &
pids+=($!)
api=http://127.0.0.1:$port/api/v1
up=0
for _ in $(seq 200); do
  up=$(curl -s --max-time 1 "$api/targets" | grep -o '"health":"up"' | wc -l || true)
  ((up >= 4)) && break
  sleep 0.1
done
((up == 4)) || fail "Prometheus reports $up of 4 targets up: $(curl -s "$api/targets" | head -c 2000)"
echo "Prometheus: 4 of 4 targets up"
query() {  # prints the value of a one-sample instant query, or nothing
  curl -s --max-time 2 "$api/query" --data-urlencode "query=$1" | grep -o '"value":\[[^]]*\]' | head -n1 |
    sed -E 's/.*,"([^"]*)"\]/\1/'
}
steps1=""
for _ in $(seq 50); do
  steps1=$(query 'sum(pamdp_env_steps_total)')
  [[ -n $steps1 ]] && break
  sleep 0.2
done
[[ -n $steps1 ]] || fail "Prometheus has no pamdp_env_steps_total"
steps2=$steps1
for _ in $(seq 50); do
  sleep 0.5
  steps2=$(query 'sum(pamdp_env_steps_total)')
  awk -v a="$steps1" -v b="$steps2" 'BEGIN { exit !(b > a) }' && break
done
echo "sum(pamdp_env_steps_total): $steps1 -> $steps2"
awk -v a="$steps1" -v b="$steps2" 'BEGIN { exit !(b > a) }' || fail "env steps did not increase in Prometheus"
for q in 'count(up{job="pamdp"} == 1)' 'sum(pamdp_replay_transitions_inserted_total)' 'max(pamdp_updates_total)' \
  'count(pamdp_process_info)'; do
  v=$(query "$q")
  echo "$q = $v"
  awk -v v="$v" 'BEGIN { exit !(v > 0) }' || fail "$q is '$v'"
done
[[ $(query 'count(up{job="pamdp"} == 1)') == 4 ]] || fail "not every target is up"
echo "metrics_cluster_test prometheus: OK"
