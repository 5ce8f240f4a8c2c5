# Shared by the system tests (tests/system/*_test.sh): a work directory removed on exit (kept on
# failure), process bookkeeping, /metrics scraping and polling. Source it after setting
#   test_name   the prefix of every message ("kill_test")
#   bin, src    the pamdp binary and the source directory
# Every assertion in these tests reads /metrics, metrics.csv or a checkpoint, never log text.
# shellcheck shell=bash

work=$(mktemp -d "/tmp/pamdp-$test_name.XXXXXX")
declare -A pid=()
cleanup() {
  for p in "${pid[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [[ ${keep:-0} == 1 ]]; then echo "kept $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT
fail() {
  echo "$test_name: FAIL: $*" >&2
  for f in "$work"/logs/*.log; do echo "--- $f"; tail -n 12 "$f"; done >&2
  keep=1
  exit 1
}
mkdir -p "$work/logs"
t0=$(date +%s.%N)
since() { awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1fs", b - a }'; }

# The value of metric NAME (with LABELS, e.g. role="replay", if given) at URL; empty if unreachable.
metric() {
  curl -sf --max-time 2 "$1" 2>/dev/null |
    awk -v name="$2" -v labels="${3:-}" '$1 == name || (index($1, name "{") == 1 && index($1, labels) > 0) { print $2; exit }' || true
}
# Polls (every 0.2 s, up to SECONDS) until the shell condition holds; fails with DESCRIPTION.
wait_for() {
  local seconds=$1 what=$2
  shift 2
  local deadline=$(($(date +%s) + seconds))
  until eval "$*"; do
    (($(date +%s) < deadline)) || fail "$what (not within ${seconds}s)"
    sleep 0.2
  done
}
ge() { awk -v a="${1:-}" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 >= b + 0) }'; }
gt() { awk -v a="${1:-}" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 > b + 0) }'; }
# The first metrics URL a process logged.
url_in() {
  grep -o 'http://127\.0\.0\.1:[0-9]*/metrics' "$1" 2>/dev/null | head -n 1 || true
}

# Options every process of a system test takes: fast heartbeats, no evaluation, frequent
# checkpoints and log rows. A test appends its own to `common` before starting the learner.
common=(--set cluster.advertise_host=127.0.0.1 --set cluster.heartbeat_ms=200 --set cluster.peer_timeout_ms=1500
  --set cluster.publish_every_updates=50 --set train.max_updates=100000000 --set train.eval_every_updates=0
  --set train.checkpoint_every_seconds=1 --set train.log_every_seconds=0.5 --set replay.warmup=200
  --set replay.shards=2 --metrics-bind 127.0.0.1 --metrics-port 0)
# Starts the learner and reads back its join and weights endpoints and metrics URL ($join,
# $weights, $lurl). $1: log name; the rest: --config/--run-dir or --resume and binds. The run
# directory must be $work/run.
start_learner() {
  local log=$work/logs/$1.log
  shift
  "$bin" learner "$@" "${common[@]}" >"$log" 2>&1 &
  pid[learner]=$!
  join=""
  wait_for 30 "the learner did not report its join endpoint" \
    'join=$(grep -o "join: *tcp://127.0.0.1:[0-9]*" "$log" | head -n1 | grep -o "tcp://.*" || true); [[ -n $join ]]'
  weights=$(grep -o "weights: *tcp://127.0.0.1:[0-9]*" "$log" | head -n1 | grep -o 'tcp://.*')
  wait_for 30 "the learner did not list its metrics URL" '[[ -s $work/run/metrics_urls.txt ]]'
  lurl=$(head -n 1 "$work/run/metrics_urls.txt")
}
declare -A surl=() aurl=()
# Starts replay shard $1 on free ports ($surl[$1]); the rest: extra `pamdp replay` options.
start_shard() {
  local i=$1
  shift
  "$bin" replay --join "$join" --insert-bind tcp://127.0.0.1:0 --sample-bind tcp://127.0.0.1:0 "$@" \
    >"$work/logs/shard-$i.log" 2>&1 &
  pid[shard$i]=$!
  local log=$work/logs/shard-$i.log  # (wait_for's conditions cannot see $i)
  wait_for 30 "shard $i did not log its metrics URL" '[[ -n $(url_in "$log") ]]'
  surl[$i]=$(url_in "$log")
}
# Starts actor $1 (seed 30 + $1) logging to $2 ($aurl[$1]); the rest: extra `pamdp actor` options.
# With wait_url=0 it does not wait for the metrics URL (many actors at once: see actor_urls).
start_actor() {
  local i=$1 name=$2
  shift 2
  "$bin" actor --join "$join" --seed $((30 + i)) "$@" >"$work/logs/$name.log" 2>&1 &
  pid[actor$i]=$!
  [[ ${wait_url:-1} == 1 ]] || return 0
  local log=$work/logs/$name.log
  wait_for 30 "actor $i did not log its metrics URL" '[[ -n $(url_in "$log") ]]'
  aurl[$i]=$(url_in "$log")
}
updates() { metric "$lurl" pamdp_updates_total; }
peers() { metric "$lurl" pamdp_learner_peers_connected "role=\"$1\""; }
# Waits until the learner's updates exceed their value now by N.
updates_grow() {
  local from
  from=$(updates)
  from=${from:-0}
  wait_for 30 "$1: learner updates stuck at $(updates) (from $from)" "gt \"\$(updates)\" $((${from%.*} + $2))"
}
