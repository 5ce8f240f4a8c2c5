#!/usr/bin/env bash
# Runs N actors of a learner on the real HFO server, one HFO server per actor (docs/hfo-server.md):
# actor i gets bin/HFO on port BASE + 10 i (HFO also takes the next two ports for its coaches) and
# joins once that server waits for its agent. A server ends its game when its actor leaves, so
# the two are restarted together if either stops. Ctrl-C stops them all.
#
#   deploy/hfo-server-actors.sh --hfo-root DIR --join tcp://LEARNER:5555 [--actors N]
#                               [--base-port P] [--seed S] [--log-dir DIR] [--goalie]
#                               [--offense-agents M [--team-actor]] [--curve-keys DIR | --insecure]
#
# A team game (--offense-agents M, 1-4): each server runs bin/HFO --offense-agents M and M actors
# join it, one per player (actor i's players are logged as actor-i-k.log); the server plays them
# in lockstep, and if any of them stops the M actors and their server are restarted together. The
# learner then needs env.offense_agents=M, so that each player's features hold its teammates.
# With --team-actor one actor per server plays all M players (pamdp actor --server-agents M: a
# thread per player, joining env.server_join_interval_ms apart), logged as actor-i.log.
#
# Defaults: 1 actor, base port 7000, seed 1 (server i of restart r: S + 100 i + r), logs in
# runs/hfo-servers. The learner runs with --set env.name=hfo-server (and train.eval_episodes=0,
# or env.server_eval_port with a server of its own); with --goalie each server gets one goalie
# (--defense-npcs 1) and the learner needs env.goalie=true. PAMDP_BIN picks the pamdp binary
# (default build/bin/pamdp; it must be built with -DHFO_ROOT); servers run as
# `/usr/bin/python3 HFO/bin/HFO ...` (HFO_PYTHON overrides the interpreter). --curve-keys and
# --insecure go to every actor as `pamdp actor` takes them: a learner on another machine needs
# one of them (CURVE with client.keys from pamdp keygen, or a trusted private network).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

hfo_root=""
join=""
actors=1
base_port=7000
seed=1
log_dir=runs/hfo-servers
goalie=0
agents=1
team_actor=0
security=()

usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; }
die() { echo "hfo-server-actors: $*" >&2; exit 2; }
need_value() { [[ $# -ge 2 && -n $2 ]] || die "$1 needs a value (see --help)"; }

while [[ $# -gt 0 ]]; do
  case $1 in
    --hfo-root) need_value "$@"; hfo_root=$2; shift 2 ;;
    --join) need_value "$@"; join=$2; shift 2 ;;
    --actors) need_value "$@"; actors=$2; shift 2 ;;
    --base-port) need_value "$@"; base_port=$2; shift 2 ;;
    --seed) need_value "$@"; seed=$2; shift 2 ;;
    --log-dir) need_value "$@"; log_dir=$2; shift 2 ;;
    --goalie) goalie=1; shift ;;
    --offense-agents) need_value "$@"; agents=$2; shift 2 ;;
    --team-actor) team_actor=1; shift ;;
    --curve-keys) need_value "$@"; security=(--curve-keys "$2"); shift 2 ;;
    --insecure) security=(--insecure); shift ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown option '$1' (see --help)" ;;
  esac
done
[[ -n $hfo_root ]] || die "--hfo-root is required (the HFO build: bin/HFO, bin/rcssserver)"
hfo_root=$(cd "$hfo_root" 2>/dev/null && pwd) || die "--hfo-root: no such directory"
[[ -x $hfo_root/bin/HFO && -x $hfo_root/bin/rcssserver ]] || die "no bin/HFO and bin/rcssserver in '$hfo_root' (run make install in HFO's build)"
[[ -n $join ]] || die "--join is required (the learner's join endpoint, tcp://HOST:PORT)"
[[ $actors =~ ^[0-9]+$ && $actors -ge 1 ]] || die "--actors must be a positive integer, got '$actors'"
[[ $base_port =~ ^[0-9]+$ && $base_port -ge 1024 && $((base_port + 10 * actors)) -le 65535 ]] ||
  die "--base-port must leave room for $actors servers 10 ports apart below 65536, got '$base_port'"
[[ $seed =~ ^[0-9]+$ ]] || die "--seed must be a non-negative integer, got '$seed'"
[[ $agents =~ ^[1-4]$ ]] || die "--offense-agents must be 1 to 4 (HFO's learned attackers per server), got '$agents'"
((team_actor == 0 || agents > 1)) || die "--team-actor plays a team of --offense-agents M > 1 in one actor; give --offense-agents"
if [[ ${security[0]:-} == --curve-keys ]]; then
  [[ -f ${security[1]}/client.keys ]] ||
    die "--curve-keys: no client.keys in '${security[1]}' (make the keys with pamdp keygen, and give the directory holding client.keys)"
fi
bin=${PAMDP_BIN:-$root/build/bin/pamdp}
[[ -x $bin ]] || die "no pamdp binary at $bin (build with -DHFO_ROOT, or set PAMDP_BIN)"
# bin/HFO starts with '#!/usr/bin/env python', and Debian 12 has no 'python': run it with python3
# (HFO_PYTHON picks another interpreter; it needs numpy).
py=""
for candidate in ${HFO_PYTHON:-} /usr/bin/python3 python3; do
  if command -v "$candidate" >/dev/null && "$candidate" -c 'import numpy' 2>/dev/null; then
    py=$candidate
    break
  fi
done
[[ -n $py ]] || die "bin/HFO needs a Python with numpy (apt-get install python3-numpy)"
mkdir -p "$log_dir"
log_dir=$(cd "$log_dir" && pwd)  # servers run there: rcssserver writes its default configs into ./~/.rcssserver
defense=()
((goalie == 0)) || defense=(--defense-npcs 1)

# One server and its actors (one per player), restarted together until this subshell is told to stop.
run_pair() {
  local i=$1 port=$((base_port + 10 * $1)) restart=0 server="" stopping=0 k name alog
  local -a team=()
  trap 'stopping=1; for a in "${team[@]}"; do kill -TERM "$a" 2>/dev/null; done; [[ -z $server ]] || kill -TERM -- "-$server" 2>/dev/null' TERM INT
  while ((stopping == 0)); do
    local log=$log_dir/hfo-$port.log
    (cd "$log_dir" && exec setsid "$py" "$hfo_root/bin/HFO" --offense-agents "$agents" "${defense[@]}" --headless \
      --fullstate --no-logging --frames-per-trial 500 --port "$port" --seed $((seed + 100 * i + restart)) >"$log" 2>&1) &
    server=$!
    team=()
    # One actor per player, or one for the team (--team-actor: it joins its players itself).
    local actors_here=$agents
    local -a per_actor=()
    if ((team_actor == 1)); then
      actors_here=1
      per_actor=(--server-agents "$agents")
    fi
    for ((k = 0; k < actors_here; k++)); do
      # HFO's trainer says it waits for an agent once per player slot; the k-th actor joins
      # after the k-th time (an agent that joins earlier breaks the server, docs/hfo-server.md).
      until (($(grep -c "Waiting for player-controlled agent" "$log" 2>/dev/null || true) > k)); do
        kill -0 "$server" 2>/dev/null || { echo "hfo-server-actors: server on port $port exited; see $log" >&2; break 2; }
        ((stopping == 0)) || break 2
        sleep 0.2
      done
      name=hfo-actor-$i
      alog=$log_dir/actor-$i.log
      if ((actors_here > 1)); then
        name=hfo-actor-$i-$k
        alog=$log_dir/actor-$i-$k.log
      fi
      # No --seed: the actor seeds its exploration from the run's seed and its index, as in
      # deploy/local-cluster.sh; the server's --seed above decides the episodes' starts.
      "$bin" actor --join "$join" --server-port "$port" --name "$name" "${per_actor[@]}" "${security[@]}" >>"$alog" 2>&1 &
      team+=($!)
    done
    if ((${#team[@]} > 0)); then
      wait -n "${team[@]}" || true  # the first actor of the team to stop ends the game
    fi
    for a in "${team[@]}"; do kill -TERM "$a" 2>/dev/null || true; done
    for a in "${team[@]}"; do wait "$a" 2>/dev/null || true; done
    team=()
    kill -TERM -- "-$server" 2>/dev/null || true
    wait "$server" 2>/dev/null || true
    server=""
    restart=$((restart + 1))
    ((stopping == 1)) || sleep 1
  done
}

pairs=()
stop_all() {
  trap - INT TERM EXIT
  echo "hfo-server-actors: stopping ${#pairs[@]} servers and their actors..." >&2
  for p in "${pairs[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap stop_all INT TERM EXIT

for ((i = 0; i < actors; i++)); do
  run_pair "$i" &
  pairs+=($!)
  if ((agents == 1 || team_actor == 1)); then
    echo "actor $i: HFO server on port $((base_port + 10 * i)), logs $log_dir/hfo-$((base_port + 10 * i)).log and $log_dir/actor-$i.log"
  else
    echo "team $i: $agents actors on the HFO server on port $((base_port + 10 * i)), logs $log_dir/hfo-$((base_port + 10 * i)).log and $log_dir/actor-$i-*.log"
  fi
done
if ((team_actor == 1)); then
  echo "hfo-server-actors: $actors servers, each with one actor playing its $agents agents, joining $join; Ctrl-C stops them and their servers"
else
  echo "hfo-server-actors: $actors servers with $agents actors each joining $join; Ctrl-C stops them and their servers"
fi
wait
