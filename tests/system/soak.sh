#!/usr/bin/env bash
# The cluster on a bad network for hours (issue 82; not in CI). A learner, 2 replay shards and 2
# actors train HFO 1v0 (deploy/configs/hfo-mpdqn.toml by default), each process in a network
# namespace of its own, every connection through tests/system/delay_relay.py (the topology of
# tests/system/netfault_test.sh), CURVE on. Every --fault-every seconds one fault, dealt
# from a deck shuffled with the seed (each kind once in every six), is injected and measured
# with a probe:
#   delay      100 +- 20 ms one way on every link, for 60 s;
#   loss       5 % of packets dropped at every host's INPUT, for 60 s;
#   partition  an actor, a shard or the learner cut off (iptables DROP in and out) for 30 s;
#   vanish     an actor's host drops everything, its process is killed (no FIN reaches anyone),
#              and a new actor in a new namespace takes its place.
# At the end it prints what was injected, what was lost (the shards' own accounting: inserted +
# restored = size + evicted; duplicates; acknowledged <= inserted <= sent over all actors, a
# killed actor counted with its last scrape), and the learning curve (metrics.csv), then plays
# the final checkpoint for --eval-episodes episodes in the embedded simulator.
#
# With --clean, the same cluster, relay and length without faults: the comparison. Two soaks may
# run at once (each makes its own namespaces and subnet from its PID).
#
# Usage: tests/system/soak.sh PATH/TO/pamdp SOURCE_DIR [--hours H] [--fault-every S] [--clean]
#          [--config FILE] [--seed N] [--out DIR] [--eval-episodes N]
# Needs root, `ip netns`, iptables with the statistic match, curl and /usr/bin/python3; exits 77
# (skipped) otherwise. The run directory, logs and summary stay in --out (default
# /tmp/pamdp-soak-PID).
set -euo pipefail
bin=$(realpath "${1:?path to pamdp}")
src=$(realpath "${2:?source dir}")
shift 2
hours=1 fault_every=300 clean=0 seed=1 out="" eval_episodes=1000
config=$src/deploy/configs/hfo-mpdqn.toml
while (($#)); do
  case $1 in
    --hours) hours=$2; shift 2 ;;
    --fault-every) fault_every=$2; shift 2 ;;
    --clean) clean=1; shift ;;
    --config) config=$(realpath "$2"); shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --eval-episodes) eval_episodes=$2; shift 2 ;;
    *) echo "soak: unknown option $1 (see the header of $0)" >&2; exit 2 ;;
  esac
done
py=/usr/bin/python3
relay_py=$src/tests/system/delay_relay.py
skip() { echo "soak: SKIPPED: $*"; exit 77; }
[[ $(id -u) -eq 0 ]] || skip "needs root (network namespaces, iptables)"
command -v ip >/dev/null || skip "needs iproute2 ('ip netns')"
command -v iptables >/dev/null || skip "needs iptables"
command -v curl >/dev/null || skip "needs curl"
[[ -x $py ]] || skip "needs /usr/bin/python3"

out=${out:-/tmp/pamdp-soak-$$}
mkdir -p "$out/logs"
work=$out
RANDOM=$seed
tag="psk$$"
net="10.$((80 + $$ % 100)).$((($$ / 100) % 250))"  # a subnet of its own
relay=$net.254
declare -A ns=() ip4=() pid=() url=() host=()
made_ns=()
cleanup() {
  for p in "${pid[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  sleep 2
  for p in "${pid[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  for n in "${made_ns[@]}"; do ip netns del "$n" 2>/dev/null || true; done
}
trap cleanup EXIT
trap 'exit 143' TERM INT HUP
t0=$(date +%s)
elapsed() { echo $(($(date +%s) - t0)); }
say() { echo "[$(date -u +%H:%M:%S) +$(elapsed)s] $*" | tee -a "$out/soak.log"; }

make_ns() {
  ip netns add "$1" || skip "'ip netns add $1' failed (no permission to make network namespaces?)"
  made_ns+=("$1")
  ip -n "$1" link set lo up
}
hub=$tag-H
make_ns "$hub"
ip netns exec "$hub" iptables -A INPUT -m statistic --mode random --probability 0.05 -j DROP 2>/dev/null ||
  skip "iptables' statistic match is unavailable"
ip netns exec "$hub" iptables -F INPUT
ip -n "$hub" link add br0 type bridge
ip -n "$hub" addr add "$relay/24" dev br0
ip -n "$hub" link set br0 up
next_octet=1
add_host() {  # NAME: a namespace with eth0 on the hub's bridge
  local h=$1 n=$tag-$1 o=$next_octet
  next_octet=$((next_octet + 1))
  make_ns "$n"
  ip -n "$n" link add eth0 type veth peer name "v$h" netns "$hub"
  ip -n "$n" addr add "$net.$o/24" dev eth0
  ip -n "$n" link set eth0 up
  ip -n "$hub" link set "v$h" master br0
  ip -n "$hub" link set "v$h" up
  ns[$h]=$n
  ip4[$h]=$net.$o
}
# Runs a command on host H. Background processes are started with `ip netns exec` itself (it execs
# the command in place), so that $! is the process and a kill reaches it.
inns() {
  local h=$1
  shift
  ip netns exec "${ns[$h]}" "$@"
}
for h in L S0 S1 A0 A1; do add_host "$h"; done

join_port=5555 weights_port=5556 echo_port=7000
declare -A insert_port=([0]=5601 [1]=5611) sample_port=([0]=5602 [1]=5612)
control=$out/relay.control
echo "0 0" >"$control"
maps=(--map "$join_port=${ip4[L]}:$join_port" --map "$weights_port=${ip4[L]}:$weights_port"
  --map "$echo_port=${ip4[L]}:$echo_port")
for i in 0 1; do
  maps+=(--map "${insert_port[$i]}=${ip4[S$i]}:${insert_port[$i]}" --map "${sample_port[$i]}=${ip4[S$i]}:${sample_port[$i]}")
done
ip netns exec "$hub" "$py" "$relay_py" relay --listen "$relay" --control "$control" "${maps[@]}" \
  >"$out/logs/relay.log" 2>&1 &
pid[relay]=$!
ip netns exec "${ns[L]}" "$py" "$relay_py" echo-server --tcp "$echo_port" --udp "$echo_port" >"$out/logs/echo.log" 2>&1 &
pid[echo]=$!

wait_until() {  # SECONDS DESCRIPTION CONDITION
  local deadline=$(($(date +%s) + $1)) what=$2
  shift 2
  until eval "$*"; do
    (($(date +%s) < deadline)) || { say "FAIL: $what"; exit 1; }
    sleep 0.5
  done
}
url_in() { grep -o 'http://127\.0\.0\.1:[0-9]*/metrics' "$1" 2>/dev/null | head -n 1 || true; }
"$bin" keygen --dir "$out/keys" >/dev/null
join=tcp://$relay:$join_port
ip netns exec "${ns[L]}" "$bin" learner --config "$config" --run-dir "$out/run" --set "seed=$seed" \
  --set "cluster.learner_bind=tcp://*:$join_port" --set "cluster.weights_bind=tcp://*:$weights_port" \
  --set "cluster.advertise_host=$relay" --set cluster.curve=true --set "cluster.curve_keys_dir=$out/keys" \
  --set replay.shards=2 --metrics-bind 127.0.0.1 --metrics-port 0 >"$out/logs/learner.log" 2>&1 &
pid[learner]=$!
wait_until 60 "the learner did not list its metrics URL" '[[ -s $out/run/metrics_urls.txt ]]'
url[learner]=$(head -n 1 "$out/run/metrics_urls.txt")
host[learner]=L
for i in 0 1; do
  ip netns exec "${ns[S$i]}" "$bin" replay --join "$join" --insert-bind "tcp://*:${insert_port[$i]}" \
    --sample-bind "tcp://*:${sample_port[$i]}" --advertise-host "$relay" --curve-keys "$out/keys" \
    --metrics-bind 127.0.0.1 --metrics-port 0 >"$out/logs/shard-$i.log" 2>&1 &
  pid[shard$i]=$!
  host[shard$i]=S$i
done
actors=()
started=0
start_actor() {  # NAME HOST
  started=$((started + 1))
  ip netns exec "${ns[$2]}" "$bin" actor --join "$join" --seed "$((seed * 100 + started))" --curve-keys "$out/keys" \
    --metrics-bind 127.0.0.1 --metrics-port 0 >"$out/logs/$1.log" 2>&1 &
  pid[$1]=$!
  host[$1]=$2
  actors+=("$1")
}
start_actor actor0 A0
start_actor actor1 A1
for name in shard0 shard1 "${actors[@]}"; do
  log=$out/logs/${name/shard/shard-}.log
  wait_until 60 "$name did not log its metrics URL" '[[ -n $(url_in "'"$log"'") ]]'
  url[$name]=$(url_in "$log")
done

scrape() { inns "${host[$1]}" curl -sf --max-time 2 "${url[$1]}" 2>/dev/null || true; }
value() { awk -v name="$2" '$1 == name { print $2; exit }' <<<"$1"; }
# The integer part of a metric, 0 when it is missing (a process that did not answer).
ival() {
  local v
  v=$(value "$@" | cut -d. -f1)
  echo "${v:-0}"
}
# Every 10 s, the counters of every live process (the accounting reads the last of each).
last=$out/last
mkdir -p "$last"
sampler_pass() {
  local name text
  for name in learner shard0 shard1 "${actors[@]}"; do
    [[ -n ${url[$name]:-} ]] || continue
    text=$(scrape "$name")
    [[ -n $text ]] || continue
    grep -E '^pamdp_(updates_total|actor_weights_version|actor_transitions_(sent|acknowledged)_total|actor_batches_lost_total|replay_(transitions_inserted_total|restored_transitions|size_transitions|transitions_evicted_total|batches_duplicate_total)|learner_peers_connected)' \
      <<<"$text" >"$last/$name.new" || true
    # Weights versions only move forward on every actor.
    if [[ $name == actor* && -s $last/$name ]]; then
      local before after
      before=$(value "$(cat "$last/$name")" pamdp_actor_weights_version)
      after=$(value "$(cat "$last/$name.new")" pamdp_actor_weights_version)
      if [[ -n $before && -n $after ]] && awk -v a="$after" -v b="$before" 'BEGIN { exit !(a < b) }'; then
        echo "$(elapsed) $name weights version went back $before -> $after" >>"$out/violations.txt"
      fi
    fi
    mv "$last/$name.new" "$last/$name"
  done
}

probe_rtt() { inns "${host[${actors[0]}]}" "$py" "$relay_py" tcp-rtt "$relay" "$echo_port" --count 10 --timeout 3 2>/dev/null | tail -n 1 || true; }
probe_loss() { inns "${host[${actors[0]}]}" "$py" "$relay_py" udp-loss "${ip4[L]}" "$echo_port" --count 300 --rate 300 --wait 1 2>/dev/null | tail -n 1 || true; }
cut_off() { inns "$1" iptables -A INPUT ! -i lo -j DROP && inns "$1" iptables -A OUTPUT ! -o lo -j DROP; }
heal() { inns "$1" iptables -F INPUT && inns "$1" iptables -F OUTPUT; }
faults=$out/faults.txt
: >"$faults"
note_fault() { echo "$(elapsed) $*" >>"$faults"; say "fault: $*"; }
replacement=0
# The six kinds (delay, loss, partition of an actor, of a shard, of the learner, vanish) are dealt
# from a deck shuffled with the seed, so every kind comes once in every six faults.
deck=()
next_kind() {
  if ((${#deck[@]} == 0)); then
    deck=(0 1 2 3 4 5)
    local i j t
    for ((i = 5; i > 0; i--)); do
      j=$((RANDOM % (i + 1))) t=${deck[i]}
      deck[i]=${deck[j]} deck[j]=$t
    done
  fi
  kind=${deck[0]}
  deck=("${deck[@]:1}")
}
inject() {
  local kind h
  next_kind
  case $kind in
    0)
      echo "100 20" >"$control"
      sleep 3
      note_fault "delay 100+-20 ms one way for 60 s ($(probe_rtt))"
      sleep 57
      echo "0 0" >"$control"
      ;;
    1)
      for h in "${!ns[@]}"; do inns "$h" iptables -A INPUT -m statistic --mode random --probability 0.05 -j DROP; done
      note_fault "loss 5 % at every host for 60 s ($(probe_loss))"
      sleep 60
      for h in "${!ns[@]}"; do inns "$h" iptables -F INPUT; done
      ;;
    2 | 3 | 4)
      local targets=(A0 S$((RANDOM % 2)) L)
      h=${targets[$((kind - 2))]}
      [[ $h == A0 ]] && h=${host[${actors[$((RANDOM % ${#actors[@]}))]}]}
      cut_off "$h"
      note_fault "partition of $h for 30 s"
      sleep 30
      heal "$h"
      ;;
    5)
      local victim=${actors[$((RANDOM % ${#actors[@]}))]} newhost
      h=${host[$victim]}
      cut_off "$h"
      sleep 2
      kill -KILL "${pid[$victim]}" 2>/dev/null || true
      unset "pid[$victim]"
      local kept=() a
      for a in "${actors[@]}"; do [[ $a == "$victim" ]] || kept+=("$a"); done
      actors=("${kept[@]}")
      mv "$last/$victim" "$last/gone-$victim" 2>/dev/null || true
      replacement=$((replacement + 1))
      newhost=R$replacement
      add_host "$newhost"
      start_actor "actor-r$replacement" "$newhost"
      wait_until 60 "the replacement actor did not log its metrics URL" \
        '[[ -n $(url_in "$out/logs/actor-r'"$replacement"'.log") ]]'
      url[actor-r$replacement]=$(url_in "$out/logs/actor-r$replacement.log")
      note_fault "vanish: $victim's host $h dropped everything, then kill -9; actor-r$replacement joined from $newhost"
      ;;
  esac
}

mode=$([[ $clean == 1 ]] && echo "clean (no faults)" || echo "a fault every $fault_every s")
say "soak: $mode, $hours h, config $(basename "$config"), seed $seed, in $out"
end=$((t0 + $(awk -v h="$hours" 'BEGIN { printf "%d", h * 3600 }')))
next_fault=$((t0 + fault_every))
while (($(date +%s) < end)); do
  kill -0 "${pid[learner]}" 2>/dev/null || { say "the learner has stopped (train.max_updates reached?)"; break; }
  sampler_pass
  if ((clean == 0 && $(date +%s) >= next_fault)); then
    inject
    next_fault=$(($(date +%s) + fault_every))
  fi
  sleep 10
done
sampler_pass

# --- the report ----------------------------------------------------------------------------------
{
  echo "== soak: $mode, $(elapsed) s"
  echo "== faults injected: $(wc -l <"$faults")"
  cat "$faults"
  echo "== accounting (live processes scraped in the order actors, shards, actors: acknowledged"
  echo "   can only lag what the shards inserted, and inserted what the actors sent; a killed actor"
  echo "   as last scraped, which may lag what it sent before it died)"
  acked=0
  for a in "${actors[@]}"; do
    acked=$((acked + $(ival "$(scrape "$a")" pamdp_actor_transitions_acknowledged_total)))
  done
  lost=0
  inserted_all=0
  for s in shard0 shard1; do
    t=$(scrape "$s")
    ins=$(value "$t" pamdp_replay_transitions_inserted_total)
    res=$(value "$t" pamdp_replay_restored_transitions)
    size=$(value "$t" pamdp_replay_size_transitions)
    ev=$(value "$t" pamdp_replay_transitions_evicted_total)
    dup=$(value "$t" pamdp_replay_batches_duplicate_total)
    stale=$(value "$t" pamdp_replay_batches_stale_total)
    missing=$(awk -v i="${ins:-0}" -v r="${res:-0}" -v s="${size:-0}" -v e="${ev:-0}" 'BEGIN { printf "%d", i + r - s - e }')
    echo "$s: inserted $ins restored $res size $size evicted $ev -> unaccounted $missing;" \
      "batches refused: ${dup:-0} duplicates (stored once), ${stale:-0} stale"
    lost=$((lost + ${missing#-}))
    inserted_all=$((inserted_all + ${ins:-0}))
  done
  sent=0
  for a in "${actors[@]}"; do
    sent=$((sent + $(ival "$(scrape "$a")" pamdp_actor_transitions_sent_total)))
  done
  for f in "$last"/gone-*; do
    [[ -f $f ]] || continue
    t=$(cat "$f")
    acked=$((acked + $(ival "$t" pamdp_actor_transitions_acknowledged_total)))
    sent=$((sent + $(ival "$t" pamdp_actor_transitions_sent_total)))
  done
  echo "actors: acknowledged $acked <= inserted $inserted_all <= sent $sent"
  ((acked <= inserted_all)) || lost=$((lost + acked - inserted_all))
  echo "accepted transitions lost: $lost"
  [[ -s $out/violations.txt ]] && { echo "violations:"; cat "$out/violations.txt"; }
  echo "== learning curve (metrics.csv: minutes, updates, episodes, success rate of the last 100)"
  awk -F, 'BEGIN { last = -1 } NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { m = int($c["wall_seconds"] / 300) } m != last { printf "%5.1f min  %9d updates  %7d episodes  %.3f\n",
      $c["wall_seconds"] / 60, $c["updates"], $c["episodes"], $c["success_rate_100"]; last = m }' "$out/run/metrics.csv"
  tail -n 1 "$out/run/metrics.csv" | awk -F, '{ printf "final: %d updates at %.1f min\n", $2, $1 / 60 }'
} | tee "$out/summary.txt"
kill -TERM "${pid[learner]}" 2>/dev/null || true
wait "${pid[learner]}" 2>/dev/null || true
if [[ -f $out/run/checkpoint.ckpt && $eval_episodes -gt 0 ]]; then
  "$bin" eval --checkpoint "$out/run/checkpoint.ckpt" --episodes "$eval_episodes" --seed 7 --json 2>/dev/null |
    tail -n 1 | tee -a "$out/summary.txt"
fi
