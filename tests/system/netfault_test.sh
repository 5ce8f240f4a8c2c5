#!/usr/bin/env bash
# The cluster across a bad network (issue 82). One network namespace per host (learner L, replay
# shards S0 and S1, actors A0 and A1, later A2) joined by a bridge in a hub namespace H; toy
# ReachStop task, CURVE on every socket. Every cluster connection goes through
# tests/system/delay_relay.py in H: the learner and the shards bind fixed ports on tcp://*, and
# everything is advertised as the relay's address 10.78.0.254, which forwards each port to its
# host and can delay every byte (one way, per direction). Faults, each measured with a probe
# before the cluster is judged under it (the measurement is printed):
#   delay     100 +- 20 ms one way on every link (the relay)   TCP echo through the relay: RTT ~ 200 ms
#   loss      5 % of packets dropped at every host's INPUT     500 UDP datagrams A0 -> L -> A0: ~ 1 - .95^2
#   partition A0, then S0, then L cut off for 30 s each        (iptables DROP in and out, lo kept): UDP probe 100 % lost
#   vanish    A1 cut off, then kill -9 (no FIN ever reaches anyone); a new actor A2 in a new namespace joins
# Assertions (all from /metrics, read inside each namespace on its loopback, and the run directory):
#   - updates keep coming (grow by > 50) under delay, under loss, while an actor or a shard is cut off;
#   - while the learner is cut off it stays alive, pamdp_updates_total never goes back, its run
#     directory stays readable (checkpoint decodes with flatc, metrics.csv's updates never go back);
#   - after the learner is back, 2 shards and 2 actors are counted again; after A1 vanished, the
#     learner counts 1 actor, then 2 with A2;
#   - after each fault ends, within RECOVER_WITHIN s (measured in 1 s steps, at most RECOVER_CAP s):
#     the learner's updates/s over the last 2 s is back to >= 0.7 x its rate over 2 s before the
#     fault (not the baseline: the machine's other load changes the pace in 3 minutes), and the
#     healed host works and is counted again: A0 sends transitions and the learner counts 2 actors;
#     S0 inserts and is sampled and the learner counts 2 shards; after L, both actors receive new
#     weights and the learner counts 2 shards and 2 actors;
#   - 4 s after A0 is cut off, `pamdp monitor --once --json` on the learner lists it, and only it,
#     among the silent peers;
#   - sampled every second: every actor's pamdp_actor_weights_version and the learner's
#     pamdp_updates_total never decrease;
#   - at the end, per shard: inserted + restored == size + evicted (without
#     pamdp_replay_transitions_evicted_total: size <= inserted + restored), duplicates == 0 (if
#     exported); over all actors: acknowledged (if exported) <= inserted (all shards) <= sent (a
#     killed actor counts with its last sample).
# Skips (exit 77) without root, `ip netns`, iptables or its `statistic` match.
# Usage: tests/system/netfault_test.sh PATH/TO/pamdp SOURCE_DIR
# Environment: RECOVER_WITHIN (10), RECOVER_CAP (15), PARTITION_S (30), LEARNER_SETS (extra
# learner options, e.g. "--set cluster.requests_in_flight_per_shard=32"). The namespaces, veths,
# bridge and iptables rules live only in the test's namespaces and go with them on exit; the
# work directory is kept when a check failed.
set -euo pipefail
bin=${1:?path to pamdp}
bin=$(realpath "$bin")
src=$(cd "${2:?source dir}" && pwd)
test_name=netfault_test
RECOVER_WITHIN=${RECOVER_WITHIN:-10}
RECOVER_CAP=${RECOVER_CAP:-15}
PARTITION_S=${PARTITION_S:-30}
py=/usr/bin/python3
relay_py=$src/tests/system/delay_relay.py

skip() {
  echo "$test_name: SKIPPED: $*"
  exit 77
}
[[ $(id -u) -eq 0 ]] || skip "needs root (network namespaces, veth, iptables)"
command -v ip >/dev/null || skip "needs ip (iproute2) for network namespaces"
command -v iptables >/dev/null || skip "needs iptables"
command -v curl >/dev/null || skip "needs curl to read /metrics"
[[ -x $py ]] || skip "needs /usr/bin/python3 for the delay relay"

# shellcheck source=tests/system/cluster_lib.sh
source "$src/tests/system/cluster_lib.sh"

# --- hosts ---------------------------------------------------------------------------------------
declare -A ns=() ip4=()
hub="pnf$$-H"
made_ns=()
stop_sampler() {  # the sampler's curl and awk first, so that nothing writes after it is gone
  [[ -n ${pid[sampler]:-} ]] || return 0
  pkill -KILL -P "${pid[sampler]}" 2>/dev/null || true
  kill -KILL "${pid[sampler]}" 2>/dev/null || true
  wait "${pid[sampler]}" 2>/dev/null || true
  unset 'pid[sampler]'
}
teardown() {
  set +e
  stop_sampler
  for p in "${pid[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null  # (reaped here, bash reports no "Killed" jobs)
  for n in "${made_ns[@]}"; do ip netns del "$n" 2>/dev/null; done
  cleanup
}
trap teardown EXIT
trap 'exit 143' TERM INT HUP
make_ns() {
  ip netns add "$1" 2>/dev/null || return 1
  made_ns+=("$1")
  ip -n "$1" link set lo up
}
make_ns "$hub" || skip "'ip netns add' failed (no permission to make network namespaces?)"
ip netns exec "$hub" iptables -S >/dev/null 2>&1 || skip "iptables does not work inside a network namespace"
ip netns exec "$hub" iptables -A INPUT -m statistic --mode random --probability 0.05 -j DROP 2>/dev/null ||
  skip "iptables' statistic match (xt_statistic) is unavailable"
ip netns exec "$hub" iptables -F INPUT
ip -n "$hub" link add br0 type bridge || skip "cannot make a bridge in a namespace"
ip -n "$hub" addr add 10.78.0.254/24 dev br0
ip -n "$hub" link set br0 up
relay=10.78.0.254
# add_host NAME LAST_OCTET: a namespace with eth0 (10.78.0.N/24) on the hub's bridge.
add_host() {
  local h=$1 n="pnf$$-$1"
  make_ns "$n" || fail "cannot make namespace $n"
  ip -n "$n" link add eth0 type veth peer name "v$h" netns "$hub"
  ip -n "$n" addr add "10.78.0.$2/24" dev eth0
  ip -n "$n" link set eth0 up
  ip -n "$hub" link set "v$h" master br0
  ip -n "$hub" link set "v$h" up
  ns[$h]=$n
  ip4[$h]=10.78.0.$2
}
inns() {
  local h=$1
  shift
  ip netns exec "${ns[$h]}" "$@"
}
add_host L 1
add_host S0 2
add_host S1 3
add_host A0 4
add_host A1 5
hosts=(L S0 S1 A0 A1)

# --- the relay and the probes --------------------------------------------------------------------
join_port=5555 weights_port=5556 echo_port=7000
declare -A insert_port=([0]=5601 [1]=5611) sample_port=([0]=5602 [1]=5612)
control=$work/relay.control
echo "0 0" >"$control"
maps=(--map "$join_port=${ip4[L]}:$join_port" --map "$weights_port=${ip4[L]}:$weights_port"
  --map "$echo_port=${ip4[L]}:$echo_port")
for i in 0 1; do
  maps+=(--map "${insert_port[$i]}=${ip4[S$i]}:${insert_port[$i]}" --map "${sample_port[$i]}=${ip4[S$i]}:${sample_port[$i]}")
done
ip netns exec "$hub" "$py" "$relay_py" relay --listen "$relay" --control "$control" "${maps[@]}" \
  >"$work/logs/relay.log" 2>&1 &
pid[relay]=$!
# A TCP and UDP echo server on L: the TCP one through the relay measures the delay, the UDP one
# (direct, host to host) loss and partitions.
ip netns exec "${ns[L]}" "$py" "$relay_py" echo-server --tcp "$echo_port" --udp "$echo_port" >"$work/logs/echo.log" 2>&1 &
pid[echo]=$!
wait_for 10 "the relay did not start" 'grep -q "relay ready" "$work/logs/relay.log"'
wait_for 10 "the echo server did not start" 'grep -q "echo server ready" "$work/logs/echo.log"'
# rtt FROM: median TCP round trip (ms) from host FROM to L's echo through the relay ("" if it failed).
rtt() {
  local out
  out=$(inns "$1" "$py" "$relay_py" tcp-rtt "$relay" "$echo_port" --count "${2:-20}" --timeout 3 || true)
  echo "$out" >>"$work/logs/probes.log"
  sed -nE 's/.*median=([0-9.]+).*/\1/p' <<<"$out"
}
# udp_loss FROM COUNT: the fraction of COUNT UDP datagrams from FROM to L and back that were lost.
udp_loss() {
  local out
  out=$(inns "$1" "$py" "$relay_py" udp-loss "${ip4[L]}" "$echo_port" --count "$2" --rate 500 --wait 1 || true)
  echo "$1: $out" >>"$work/logs/probes.log"
  sed -nE 's/.*loss=([0-9.]+).*/\1/p' <<<"$out"
}
for h in "${hosts[@]}"; do
  [[ -n $(rtt "$h" 1) ]] || fail "host $h gets no echo from L through the relay on the clean network"
done
clean_rtt=$(rtt A0)
clean_loss=$(udp_loss A0 200)
[[ -n $clean_rtt ]] || fail "no TCP round trip through the relay on the clean network"
echo "network up at $(since): clean RTT A0 -> relay -> L ${clean_rtt} ms, UDP loss A0 <-> L $clean_loss"

# --- the cluster ---------------------------------------------------------------------------------
"$bin" keygen --dir "$work/keys" >/dev/null
common=(--set cluster.heartbeat_ms=200 --set cluster.peer_timeout_ms=1500
  --set cluster.publish_every_updates=50 --set train.max_updates=100000000 --set train.eval_every_updates=0
  --set train.checkpoint_every_seconds=1 --set train.log_every_seconds=0.5 --set replay.warmup=200
  --set replay.shards=2 --metrics-bind 127.0.0.1 --metrics-port 0)
join=tcp://$relay:$join_port
procs=$work/procs.txt  # NAME NAMESPACE METRICS_URL, read by the sampler
: >"$procs"
declare -A url=() host=()
register() {  # NAME HOST URL
  url[$1]=$3
  host[$1]=$2
  echo "$1 ${ns[$2]} $3" >>"$procs"
}
ip netns exec "${ns[L]}" "$bin" learner --config "$src/deploy/configs/reach_stop.toml" --run-dir "$work/run" \
  --set "cluster.learner_bind=tcp://*:$join_port" --set "cluster.weights_bind=tcp://*:$weights_port" \
  --set "cluster.advertise_host=$relay" --set cluster.curve=true --set "cluster.curve_keys_dir=$work/keys" \
  "${common[@]}" ${LEARNER_SETS:-} >"$work/logs/learner.log" 2>&1 &
pid[learner]=$!
wait_for 30 "the learner did not list its metrics URL" '[[ -s $work/run/metrics_urls.txt ]]'
register learner L "$(head -n 1 "$work/run/metrics_urls.txt")"
start_shard() {
  local i=$1 log=$work/logs/shard-$1.log
  ip netns exec "${ns[S$i]}" "$bin" replay --join "$join" --insert-bind "tcp://*:${insert_port[$i]}" \
    --sample-bind "tcp://*:${sample_port[$i]}" --advertise-host "$relay" --curve-keys "$work/keys" \
    --metrics-bind 127.0.0.1 --metrics-port 0 >"$log" 2>&1 &
  pid[shard$i]=$!
  wait_for 30 "shard $i did not log its metrics URL" '[[ -n $(url_in "$log") ]]'
  register "shard$i" "S$i" "$(url_in "$log")"
}
start_actor() {
  local i=$1 log=$work/logs/actor-$1.log
  ip netns exec "${ns[A$i]}" "$bin" actor --join "$join" --seed $((30 + i)) --curve-keys "$work/keys" \
    --metrics-bind 127.0.0.1 --metrics-port 0 >"$log" 2>&1 &
  pid[actor$i]=$!
  wait_for 30 "actor $i did not log its metrics URL" '[[ -n $(url_in "$log") ]]'
  register "actor$i" "A$i" "$(url_in "$log")"
}
start_shard 0
start_shard 1
start_actor 0
start_actor 1

# --- metrics -------------------------------------------------------------------------------------
# scrape NAME: the /metrics text of process NAME, read inside its namespace ("" if unreachable).
scrape() { inns "${host[$1]}" curl -sf --max-time 2 "${url[$1]}" 2>/dev/null || true; }
# value TEXT NAME [LABELS]: a metric's value in a scrape.
value() {
  awk -v name="$2" -v labels="${3:-}" '$1 == name || (index($1, name "{") == 1 && index($1, labels) > 0) { print $2; exit }' <<<"$1"
}
lmetric() { value "$(scrape learner)" "$@"; }
updates() { lmetric pamdp_updates_total; }
peers() { lmetric pamdp_learner_peers_connected "role=\"$1\""; }
now() { date +%s.%N; }
# The sampler: every second, the counters of every process in $procs, as "T NAME METRIC VALUE".
samples=$work/samples.txt
sampled='^pamdp_(updates_total|learner_peers_connected|learner_weights_version|actor_weights_version|actor_transitions_sent_total|actor_transitions_acknowledged_total|actor_batches_(sent|acknowledged|lost)_total|replay_transitions_inserted_total|replay_restored_transitions|replay_size_transitions|replay_transitions_evicted_total|replay_batches_duplicate_total)'
sampler() {
  local name n u t
  while true; do
    while read -r name n u; do
      t=$(now)
      ip netns exec "$n" curl -sf --max-time 1 "$u" 2>/dev/null |
        awk -v t="$t" -v who="$name" -v re="$sampled" '$1 ~ re { print t, who, $1, $2 }' >>"$samples" || true
    done <"$procs"
    sleep 0.7
  done
}
sampler &
pid[sampler]=$!

wait_for 40 "the cluster did not form (shards $(peers replay), actors $(peers actor))" \
  '[[ $(peers replay) == 2 && $(peers actor) == 2 ]]'
wait_for 60 "no updates through the relay" 'gt "$(updates)" 300'
echo "cluster up at $(since): updates $(updates), shards $(peers replay), actors $(peers actor)"

# --- phases --------------------------------------------------------------------------------------
failures=()
soft_fail() {
  echo "$test_name: FAIL (going on): $*" >&2
  failures+=("$*")
}
phase_names=() phase_faults=() phase_updates=() phase_recovery=() phase_back=()
# hold SECONDS [FROM]: sleeps until FROM (default now) + SECONDS, sampling the learner's updates
# every second; sets held_from/held_to and fails (softly) if pamdp_updates_total ever goes back.
hold() {
  local end u last=""
  end=$(awk -v t="${2:-$(now)}" -v s="$1" 'BEGIN { printf "%.3f", t + s }')
  held_from=$(updates)
  while awk -v t="$(now)" -v e="$end" 'BEGIN { exit !(t < e) }'; do
    sleep "$(awk -v t="$(now)" -v e="$end" 'BEGIN { d = e - t; printf "%.2f", (d < 1 ? (d > 0 ? d : 0) : 1) }')"
    u=$(updates)
    if [[ -n $u && -n $last ]] && awk -v a="$u" -v b="$last" 'BEGIN { exit !(a < b) }'; then
      soft_fail "the learner's updates went back from $last to $u"
    fi
    [[ -n $u ]] && last=$u
  done
  held_to=$(updates)
  [[ -n $held_to ]] || held_to=$last
}
# probe FUNCTION ARGS...: runs a probe (rtt, udp_loss) in the background while the test holds the
# fault; probed reads its result.
probe() {
  "$@" >"$work/probe.out" &
  probe_pid=$!
}
probed() {
  wait "$probe_pid" || true
  cat "$work/probe.out"
}
# recovery LABEL [COND WHAT]...: after a fault ends, seconds (in 1 s steps) until the learner's
# updates over the last 2 s run at >= 0.7 x baseline ($recovered), and until each shell condition
# COND holds (the healed host counted again, its traffic flowing again, described by WHAT);
# ">CAP" if not within RECOVER_CAP s. Each is asserted against RECOVER_WITHIN. Sets $recovered
# and $back ("WHAT TIME, ..." or "-").
recovery() {
  local label=$1 start t u rate i n j k all
  shift
  local -a conds=() whats=() times=() ts=() us=()
  while (($# >= 2)); do
    conds+=("$1")
    whats+=("$2")
    times+=(">$RECOVER_CAP")
    shift 2
  done
  start=$(now)
  recovered=">$RECOVER_CAP"
  for ((i = 0; ; i++)); do
    t=$(now)
    awk -v a="$t" -v b="$start" -v c="$RECOVER_CAP" 'BEGIN { exit !(a - b > c + 0.5) }' && break
    for k in "${!conds[@]}"; do
      if [[ ${times[k]} == ">"* ]] && eval "${conds[k]}"; then
        times[k]=$(awk -v a="$t" -v b="$start" 'BEGIN { printf "%.0f", a - b }')
      fi
    done
    if [[ $recovered == ">"* ]]; then
      u=$(updates)
      if [[ -n $u ]]; then
        ts+=("$t")
        us+=("$u")
      fi
      n=${#ts[@]}
      # the rate since the first sample at least 2 s back
      j=$((n - 1))
      while ((j > 0)) && awk -v a="${ts[n - 1]}" -v b="${ts[j]}" 'BEGIN { exit !(a - b < 1.95) }'; do j=$((j - 1)); done
      if ((n >= 2)) && awk -v a="${ts[n - 1]}" -v b="${ts[j]}" 'BEGIN { exit !(a - b >= 1.95) }'; then
        rate=$(awk -v u1="${us[n - 1]}" -v u0="${us[j]}" -v a="${ts[n - 1]}" -v b="${ts[j]}" 'BEGIN { printf "%.0f", (u1 - u0) / (a - b) }')
        if awk -v r="$rate" -v b="$ref" 'BEGIN { exit !(r >= 0.7 * b) }'; then
          recovered=$(awk -v a="$t" -v b="$start" 'BEGIN { printf "%.0f", a - b }')
        fi
      fi
    fi
    all=1
    [[ $recovered == ">"* ]] && all=0
    for k in "${!times[@]}"; do [[ ${times[k]} == ">"* ]] && all=0; done
    ((all)) && break
    sleep "$(awk -v s="$start" -v i="$i" -v t="$(now)" 'BEGIN { d = s + i + 1 - t; printf "%.2f", (d > 0 ? d : 0) }')"
  done
  echo "  $label: updates/s over 2 s back to >= 0.7 x the rate before the fault ($ref/s; baseline $baseline/s) after ${recovered} s (target <= $RECOVER_WITHIN s)"
  if [[ $recovered == ">"* ]] || ((recovered > RECOVER_WITHIN)); then
    soft_fail "$label: the learner's update rate took ${recovered} s to recover, more than RECOVER_WITHIN=$RECOVER_WITHIN s"
  fi
  back="-"
  for k in "${!conds[@]}"; do
    echo "  $label: ${whats[k]} after ${times[k]} s (target <= $RECOVER_WITHIN s)"
    if [[ ${times[k]} == ">"* ]] || ((times[k] > RECOVER_WITHIN)); then
      soft_fail "$label: ${whats[k]} took ${times[k]} s, more than RECOVER_WITHIN=$RECOVER_WITHIN s"
    fi
    if [[ $back == "-" ]]; then back="${whats[k]} ${times[k]}"; else back+=", ${whats[k]} ${times[k]}"; fi
  done
}
record() { # NAME FAULT UPDATES RECOVERY BACK
  phase_names+=("$1")
  phase_faults+=("$2")
  phase_updates+=("$3")
  phase_recovery+=("$4")
  phase_back+=("${5:--}")
}
delta() { awk -v a="${1:-0}" -v b="${2:-0}" 'BEGIN { printf "%.0f", a - b }'; }

# baseline: the clean network
b0=$(updates)
tb0=$(now)
sleep 8
b1=$(updates)
tb1=$(now)
baseline=$(awk -v a="$b0" -v b="$b1" -v s="$tb0" -v e="$tb1" 'BEGIN { printf "%.0f", (b - a) / (e - s) }')
((baseline > 0)) || fail "no updates on the clean network (baseline $baseline/s)"
echo "baseline at $(since): $baseline updates/s over 8 s (updates $b0 -> $b1)"
record "baseline (clean)" "RTT ${clean_rtt} ms, loss $clean_loss" "$(delta "$b1" "$b0")" "-" "-"
# The reference a recovery is judged against: the learner's rate over 2 s just before the fault,
# not the baseline of minute 0, since the other work on the machine changes its pace over the
# test's 3 minutes.
reference() {
  local u0 t0 u1 t1
  u0=$(updates)
  t0=$(now)
  sleep 2
  u1=$(updates)
  t1=$(now)
  ref=$(awk -v a="$u0" -v b="$u1" -v s="$t0" -v e="$t1" -v base="$baseline" \
    'BEGIN { if (a == "" || b == "") print base; else printf "%.0f", (b - a) / (e - s) }')
}
reference
echo "100 20" >"$control"
sleep 0.5
probe rtt A0 20
hold 10
delay_rtt=$(probed)
[[ -n $delay_rtt ]] || fail "the delay probe got no round trip"
awk -v r="$delay_rtt" 'BEGIN { exit !(r >= 170 && r <= 320) }' ||
  fail "the delay is not what the test set: RTT $delay_rtt ms through the relay, expected ~200 (2 x 100 ms)"
echo "delay at $(since): 100 +- 20 ms one way; measured RTT A0 -> relay -> L median $delay_rtt ms"
grown=$(delta "$held_to" "$held_from")
echo "  updates under delay: $held_from -> $held_to (+$grown)"
((grown > 50)) || soft_fail "updates stalled under 100 ms delay (+$grown in 10 s)"
echo "0 0" >"$control"
recovery "delay removed"
record "delay 100+-20 ms" "RTT $delay_rtt ms" "$grown" "$recovered (ref $ref)" "$back"

# loss: 5 % at every host's INPUT
reference
for h in "${hosts[@]}"; do inns "$h" iptables -A INPUT -m statistic --mode random --probability 0.05 -j DROP; done
probe udp_loss A0 500
hold 10
loss=$(probed)
[[ -n $loss ]] || fail "the loss probe failed"
awk -v l="$loss" 'BEGIN { exit !(l >= 0.03 && l <= 0.20) }' ||
  fail "the loss is not what the test set: $loss of 500 UDP round trips, expected ~0.0975 (1 - 0.95^2)"
echo "loss at $(since): 5 % per host INPUT; measured UDP round-trip loss A0 <-> L $loss (expected 1 - .95^2 = .0975)"
grown=$(delta "$held_to" "$held_from")
echo "  updates under loss: $held_from -> $held_to (+$grown)"
((grown > 50)) || soft_fail "updates stalled under 5 % loss (+$grown in 10 s)"
for h in "${hosts[@]}"; do inns "$h" iptables -D INPUT -m statistic --mode random --probability 0.05 -j DROP; done
recovery "loss removed"
record "loss 5 %/host" "UDP RTT loss $loss" "$grown" "$recovered (ref $ref)" "$back"

cut() {
  inns "$1" iptables -A INPUT ! -i lo -j DROP
  inns "$1" iptables -A OUTPUT ! -o lo -j DROP
}
heal() {
  inns "$1" iptables -D INPUT ! -i lo -j DROP
  inns "$1" iptables -D OUTPUT ! -o lo -j DROP
}
# partition HOST PROBE_FROM: cuts HOST off for PARTITION_S s (probed with UDP from PROBE_FROM to
# L), samples the learner's updates meanwhile, heals it.
partition() {
  local h=$1 from=$2
  reference
  cut "$h"
  local cut_at
  cut_at=$(now)
  echo "partition of $h at $(since) ($(date +%T)) for ${PARTITION_S} s"
  probe udp_loss "$from" 50
  [[ $h == A0 ]] && monitor_marks_silent "$cut_at"
  # The counters the "back" conditions compare with, halfway (they stand still while the host is
  # cut off, and reading them takes seconds on a loaded machine).
  hold "$((PARTITION_S / 2))" "$cut_at"
  partition_from=$held_from
  at_heal=$(counters)
  hold "$PARTITION_S" "$cut_at"
  partition_to=$held_to
  partition_probe=$(probed)
  heal "$h"
  [[ $partition_probe == 1.0000 ]] || fail "the partition of $h leaks: UDP loss $from <-> L $partition_probe, expected 1"
  echo "  measured UDP loss $from <-> L while $h was cut off: $partition_probe"
  echo "  $h healed at $(since) ($(date +%T))"
}
# monitor_marks_silent CUT_AT: 4 s after the cut, `pamdp monitor --once --json` (two scrapes a
# second apart) on the learner's /metrics must list exactly one silent actor (A0; A1 talks on):
# a silent peer is marked within 5 s.
monitor_marks_silent() {
  sleep "$(awk -v c="$1" -v t="$(now)" 'BEGIN { d = c + 4 - t; printf "%.2f", (d > 0 ? d : 0) }')"
  local frame silent started
  started=$(awk -v c="$1" -v t="$(now)" 'BEGIN { printf "%.1f", t - c }')
  frame=$(inns L "$bin" monitor "${url[learner]}" --once --json 2>/dev/null | tail -n 1 || true)
  silent=$("$py" -c 'import json, sys
peers = json.loads(sys.stdin.read()).get("silent_peers", [])
print(sum(1 for p in peers if p["peer"].startswith("actor:")))' <<<"$frame" 2>/dev/null || echo "?")
  echo "  pamdp monitor started $started s after the cut (scrapes then and 1 s later): $silent silent actor(s)"
  [[ $silent == 1 ]] || soft_fail "pamdp monitor did not mark A0 silent within 5 s (silent actors: $silent; frame: ${frame:0:300})"
}
# counters: the values the "back" conditions compare with, read while the host is cut off.
counters() {
  echo "a0_sent=$(value "$(scrape actor0)" pamdp_actor_transitions_sent_total)"
  local s0
  s0=$(scrape shard0)
  echo "s0_inserted=$(value "$s0" pamdp_replay_transitions_inserted_total)"
  echo "s0_sampled=$(value "$s0" pamdp_replay_transitions_sampled_total)"
  echo "a0_version=$(value "$(scrape actor0)" pamdp_actor_weights_version)"
  echo "a1_version=$(value "$(scrape actor1)" pamdp_actor_weights_version)"
}
at() { sed -n "s/^$1=//p" <<<"$at_heal"; }
# What "back" means for each host: its traffic flowing again, and counted by the learner again.
sending_A0='gt "$(value "$(scrape actor0)" pamdp_actor_transitions_sent_total)" "$(at a0_sent)"'
counted_A0='[[ $(peers actor) == 2 ]]'
working_S0='s=$(scrape shard0) && gt "$(value "$s" pamdp_replay_transitions_inserted_total)" "$(at s0_inserted)" && gt "$(value "$s" pamdp_replay_transitions_sampled_total)" "$(at s0_sampled)"'
counted_S0='[[ $(peers replay) == 2 ]]'
weights_L='gt "$(value "$(scrape actor0)" pamdp_actor_weights_version)" "$(at a0_version)" && gt "$(value "$(scrape actor1)" pamdp_actor_weights_version)" "$(at a1_version)"'
counted_L='[[ $(peers replay) == 2 && $(peers actor) == 2 ]]'


for victim in A0 S0; do
  partition "$victim" "$victim"
  grown=$(delta "$partition_to" "$partition_from")
  echo "  updates while $victim was cut off: $partition_from -> $partition_to (+$grown)"
  ((grown > 50)) || soft_fail "updates stalled while $victim was cut off (+$grown)"
  case $victim in
    A0) recovery "A0 healed" "$sending_A0" "A0 sending" "$counted_A0" "A0 counted" ;;
    S0) recovery "S0 healed" "$working_S0" "S0 inserting+sampled" "$counted_S0" "S0 counted" ;;
  esac
  record "partition $victim ${PARTITION_S} s" "UDP loss $partition_probe" "$grown" "$recovered (ref $ref)" "$back"
done

# The learner cut off from everything: it stays alive, its counters never go back, its run
# directory stays readable; afterwards the same shards and actors are counted again.
ckpt_updates() {
  cp "$work/run/checkpoint.ckpt" "$work/probe.ckpt" 2>/dev/null || return 0
  (cd "$work" && flatc --json --strict-json --raw-binary "$src/schemas/checkpoint.fbs" -- probe.ckpt 2>/dev/null) || return 0
  grep -o '"updates": *[0-9]*' "$work/probe.json" | grep -o '[0-9]*$' || true
}
partition L A0
grown=$(delta "$partition_to" "$partition_from")
kill -0 "${pid[learner]}" 2>/dev/null || fail "the learner died while it was cut off"
echo "  updates while L was cut off: $partition_from -> $partition_to (+$grown)"
for f in checkpoint.ckpt metrics.csv episodes.csv metrics_urls.txt; do
  [[ -s $work/run/$f ]] || soft_fail "the run directory lost $f while the learner was cut off"
done
ck=$(ckpt_updates)
[[ -n $ck ]] || soft_fail "the learner's checkpoint does not decode after the partition"
recovery "L healed" "$weights_L" "new weights at A0+A1" "$counted_L" "2+2 counted"
record "partition L ${PARTITION_S} s" "UDP loss $partition_probe" "$grown" "$recovered (ref $ref)" "$back"
wait_for 30 "after the learner's partition the cluster did not come back (shards $(peers replay), actors $(peers actor))" \
  '[[ $(peers replay) == 2 && $(peers actor) == 2 ]]'
for p in shard0 shard1 actor0 actor1; do
  kill -0 "${pid[$p]}" 2>/dev/null || soft_fail "$p exited during the partitions"
done
echo "  after L healed: shards $(peers replay), actors $(peers actor), checkpoint at $ck updates, learner at $(updates)"

# A1 vanishes without a FIN: everything but lo dropped, then kill -9; A2 joins in its place.
vanished_at=$(now)
cut A1
vanish_probe=$(udp_loss A1 50)
[[ $vanish_probe == 1.0000 ]] || fail "A1 is not cut off: UDP loss A1 <-> L $vanish_probe, expected 1"
actor1_last=$(scrape actor1)
kill -KILL "${pid[actor1]}"
wait "${pid[actor1]}" 2>/dev/null || true
unset 'pid[actor1]'
grep -v '^actor1 ' "$procs" >"$procs.new" && mv "$procs.new" "$procs"
wait_for 30 "the learner still counts 2 actors after A1 vanished" '[[ $(peers actor) == 1 ]]'
noticed=$(delta "$(now)" "$vanished_at")
echo "vanish of A1 at $(since) ($(date +%T)): UDP loss A1 <-> L $vanish_probe, then kill -9; the learner counted 1 actor ~${noticed} s after the cut"
add_host A2 6
hosts+=(A2)
v0=$(updates)
start_actor 2
wait_for 40 "A2 was not counted (actors $(peers actor))" '[[ $(peers actor) == 2 ]]'
updates_grow_by() {
  local from=$1 n=$2
  wait_for 30 "$3: learner updates stuck at $(updates) (from $from)" "gt \"\$(updates)\" $((${from%.*} + n))"
}
updates_grow_by "$v0" 100 "A2 joined"
v1=$(updates)
echo "  A2 joined: actors $(peers actor), updates $v0 -> $v1"
record "vanish A1, A2 joins" "no FIN; 1 actor ${noticed} s after cut" "$(delta "$v1" "$v0")" "-" "-"

# --- accounting ----------------------------------------------------------------------------------
stop_sampler
# Never back: every actor's weights version and the learner's updates, over all samples.
went_back=$(awk '$3 == "pamdp_actor_weights_version" || $3 == "pamdp_updates_total" {
  k = $2 " " $3; if (k in last && $4 + 0 < last[k]) { print $2 ": " $3 " " last[k] " -> " $4 " at " $1; exit } last[k] = $4 + 0 }' "$samples")
[[ -z $went_back ]] || soft_fail "a counter went back: $went_back"
n_samples=$(wc -l <"$samples")
# Actors first (acknowledged), then shards (inserted), then actors again (sent): each inequality
# compares a value read before with one read after.
sum_actors() {  # METRIC: over the live actors, plus A1's last sample
  local total=0 name v
  for name in actor0 actor2; do
    v=$(value "$(scrape "$name")" "$1")
    [[ -n $v ]] || { echo ""; return; }
    total=$(awk -v a="$total" -v b="$v" 'BEGIN { printf "%.0f", a + b }')
  done
  v=$(value "$actor1_last" "$1")
  [[ -n $v ]] || { echo ""; return; }
  awk -v a="$total" -v b="$v" 'BEGIN { printf "%.0f", a + b }'
}
acked=$(sum_actors pamdp_actor_transitions_acknowledged_total)
inserted_all=0
notes=()
shard_rows=()
for i in 0 1; do
  s=$(scrape "shard$i")
  [[ -n $s ]] || fail "shard $i's /metrics did not answer at the end"
  ins=$(value "$s" pamdp_replay_transitions_inserted_total)
  res=$(value "$s" pamdp_replay_restored_transitions)
  size=$(value "$s" pamdp_replay_size_transitions)
  ev=$(value "$s" pamdp_replay_transitions_evicted_total)
  dup=$(value "$s" pamdp_replay_batches_duplicate_total)
  res=${res:-0}
  inserted_all=$(awk -v a="$inserted_all" -v b="$ins" 'BEGIN { printf "%.0f", a + b }')
  if [[ -n $ev ]]; then
    awk -v i="$ins" -v r="$res" -v s="$size" -v e="$ev" 'BEGIN { exit !(i + r == s + e) }' ||
      soft_fail "shard $i: inserted $ins + restored $res != size $size + evicted $ev"
  else
    notes+=("shard $i exports no pamdp_replay_transitions_evicted_total: checked size <= inserted + restored only")
    awk -v i="$ins" -v r="$res" -v s="$size" 'BEGIN { exit !(s <= i + r) }' ||
      soft_fail "shard $i: size $size > inserted $ins + restored $res"
  fi
  if [[ -n $dup ]]; then
    [[ ${dup%.*} == 0 ]] || soft_fail "shard $i stored $dup duplicate batches"
  else
    notes+=("shard $i exports no pamdp_replay_batches_duplicate_total: duplicates not checked")
  fi
  shard_rows+=("shard $i: inserted ${ins} restored ${res} size ${size} evicted ${ev:-n/a} duplicates ${dup:-n/a}")
done
sent_all=$(sum_actors pamdp_actor_transitions_sent_total)
[[ -n $sent_all ]] || fail "an actor exports no pamdp_actor_transitions_sent_total"
awk -v i="$inserted_all" -v s="$sent_all" 'BEGIN { exit !(i <= s) }' ||
  soft_fail "the shards inserted $inserted_all transitions, the actors sent only $sent_all"
if [[ -n $acked ]]; then
  awk -v a="$acked" -v i="$inserted_all" 'BEGIN { exit !(a <= i) }' ||
    soft_fail "the actors count $acked transitions acknowledged, the shards inserted only $inserted_all"
else
  notes+=("the actors export no pamdp_actor_transitions_acknowledged_total: acknowledged <= inserted not checked")
fi
# metrics.csv's updates never go back (the learner's own log across the partitions)
csv_back=$(awk -F, 'NR > 2 && $2 < prev { print NR ": " prev " -> " $2; exit } NR > 1 { prev = $2 }' "$work/run/metrics.csv")
[[ -z $csv_back ]] || soft_fail "metrics.csv's updates go back (line $csv_back)"
kill -0 "${pid[learner]}" 2>/dev/null || soft_fail "the learner is not alive at the end"

# --- summary -------------------------------------------------------------------------------------
echo
echo "netfault_test summary (baseline $baseline updates/s; rate back: s until updates/s over 2 s >= 0.7 x the rate before the fault; host back: s until the healed host works and is counted again; target <= $RECOVER_WITHIN s)"
printf '%-22s | %-30s | %8s | %-16s | %s\n' phase "measured fault" updates "rate back s" "host back (s)"
for k in "${!phase_names[@]}"; do
  printf '%-22s | %-30s | %8s | %-16s | %s\n' "${phase_names[$k]}" "${phase_faults[$k]}" "${phase_updates[$k]}" "${phase_recovery[$k]}" "${phase_back[$k]}"
done
echo "accounting ($n_samples samples of counters, none went back${went_back:+: NO, $went_back}):"
for r in "${shard_rows[@]}"; do echo "  $r"; done
echo "  actors: acknowledged ${acked:-n/a} <= inserted $inserted_all <= sent $sent_all (A1 from its last sample)"
for n in "${notes[@]}"; do echo "  note: $n"; done
if ((${#failures[@]} > 0)); then
  keep=1
  echo "$test_name: FAIL: ${#failures[@]} check(s) failed in $(since):" >&2
  for f in "${failures[@]}"; do echo "  - $f" >&2; done
  exit 1
fi
echo "$test_name: OK in $(since)"
