#!/usr/bin/env bash
# Runs the main job on this machine: a local actor-learner cluster training DDPG on the embedded
# HFO simulator. Starts K replay shards, the learner and N actors, shows the learner's progress,
# and on Ctrl-C stops every process it started, leaving a resumable run directory.
#
#   deploy/local-cluster.sh [--actors N] [--shards K] [--config FILE] [--run-dir DIR]
#                           [--resume DIR] [--port P] [--duration SECONDS] [--curve] [--set key=value ...]
#
# Defaults: one actor per core, 2 shards, deploy/configs/fast.toml, runs/cluster-<time>,
# learner on 127.0.0.1:5555 (weights on 5556; --port 0: any free ports). --curve encrypts and
# authenticates every socket with CURVE, with keys made by `pamdp keygen` into RUN_DIR/keys (kept
# for --resume). Builds build/bin/pamdp first if it is missing (PAMDP_BIN=path/to/pamdp runs
# another build instead).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

cores=$(nproc 2>/dev/null || echo 2)
actors=$cores
shards=2
config=deploy/configs/fast.toml
run_dir=""
resume=""
port=5555
duration=0
curve=0
sets=()

usage() { sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "local-cluster: $*" >&2; exit 2; }
need_value() { [[ $# -ge 2 && -n $2 ]] || die "$1 needs a value (see --help)"; }

while [[ $# -gt 0 ]]; do
  case $1 in
    --actors) need_value "$@"; actors=$2; shift 2 ;;
    --shards) need_value "$@"; shards=$2; shift 2 ;;
    --config) need_value "$@"; config=$2; shift 2 ;;
    --run-dir) need_value "$@"; run_dir=$2; shift 2 ;;
    --resume) need_value "$@"; resume=$2; shift 2 ;;
    --port) need_value "$@"; port=$2; shift 2 ;;
    --duration) need_value "$@"; duration=$2; shift 2 ;;
    --curve) curve=1; shift ;;
    --set) need_value "$@"; sets+=(--set "$2"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown option '$1' (see --help)" ;;
  esac
done
[[ $actors =~ ^[0-9]+$ && $actors -ge 1 ]] || die "--actors must be a positive integer, got '$actors'"
[[ $shards =~ ^[0-9]+$ && $shards -ge 1 ]] || die "--shards must be a positive integer, got '$shards'"
[[ $port =~ ^[0-9]+$ && $port -le 65534 ]] || die "--port must be within 0..65534 (0: any free ports), got '$port'"
[[ $duration =~ ^[0-9]+$ ]] || die "--duration must be a whole number of seconds, got '$duration'"
if [[ -z $resume ]]; then
  [[ -f $config ]] || die "config '$config' not found (presets: deploy/configs/*.toml)"
fi

if [[ -n ${PAMDP_BIN:-} ]]; then
  [[ -x $PAMDP_BIN ]] || die "PAMDP_BIN=$PAMDP_BIN is not an executable"
elif [[ ! -x build/bin/pamdp ]]; then
  echo "local-cluster: building build/bin/pamdp (first run)..." >&2
  deploy/install-deps.sh
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build --target pamdp -j "$cores" >/dev/null
fi
bin=${PAMDP_BIN:-$root/build/bin/pamdp}

if ((port > 0)); then
  for p in $port $((port + 1)); do
    if (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then
      die "port $p on 127.0.0.1 is in use (another cluster?); pick others with --port (0: any free ports)"
    fi
  done
fi

if [[ -n $resume ]]; then
  run_dir=$resume
  # A run started with --curve goes on with CURVE (its config says cluster.curve = true).
  [[ -f $run_dir/keys/client.keys ]] && curve=1
  [[ -f $run_dir/checkpoint.ckpt ]] || die "--resume $run_dir: no checkpoint.ckpt there"
  learner_args=(--resume "$run_dir")
else
  [[ -n $run_dir ]] || run_dir="runs/cluster-$(date +%Y%m%d-%H%M%S)"
  [[ ! -e $run_dir/checkpoint.ckpt ]] || die "run directory '$run_dir' already holds a run; continue it with --resume $run_dir"
  learner_args=(--config "$config" --run-dir "$run_dir")
fi
mkdir -p "$run_dir/logs"
if ((port > 0)); then
  join="tcp://127.0.0.1:$port"
  weights="tcp://127.0.0.1:$((port + 1))"
else
  join="tcp://127.0.0.1:0"
  weights="tcp://127.0.0.1:0"
fi
learner_curve=()
peer_curve=()
if ((curve)); then
  # Fresh keys for a new run; a resumed run keeps its own (its actors and shards may still hold them).
  keys=$run_dir/keys
  if [[ ! -f $keys/client.keys ]]; then
    "$bin" keygen --dir "$keys" >/dev/null || die "pamdp keygen --dir $keys failed"
  fi
  learner_curve=(--set cluster.curve=true --set "cluster.curve_keys_dir=$keys")
  peer_curve=(--curve-keys "$keys")
fi

pids=()
final_shown=0
stop_all() {
  trap - INT TERM EXIT
  echo
  echo "local-cluster: stopping ${#pids[@]} processes..." >&2
  # Actors first (no new data), then the learner (writes its checkpoint), then the shards
  # (write their snapshots).
  for pid in "${pids[@]:1+shards}"; do kill -TERM "$pid" 2>/dev/null || true; done
  kill -TERM "${pids[0]}" 2>/dev/null || true
  wait "${pids[0]}" 2>/dev/null || true
  for pid in "${pids[@]:1:shards}"; do kill -TERM "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  # The learner's final line ("learner stopped: N updates, ...") on the terminal too, not only in
  # its log, when the tail that showed the log stopped before the learner wrote it (Ctrl-C,
  # --duration).
  if ((!final_shown)) && [[ -f $run_dir/logs/learner.log ]]; then
    grep -E "^learner stopped:" "$run_dir/logs/learner.log" | tail -n 1 || true
  fi
  echo "local-cluster: stopped. Resume with: deploy/local-cluster.sh --resume $run_dir" >&2
  if [[ ${env_name:-} == hfo* ]]; then
    echo "local-cluster: HFO takes tens of minutes to learn; a success rate near 0.00 in the first minutes is expected" >&2
  fi
}
trap stop_all INT TERM EXIT

"$bin" learner "${learner_args[@]}" \
  --set "cluster.learner_bind=$join" --set "cluster.weights_bind=$weights" \
  --set "replay.shards=$shards" "${learner_curve[@]}" "${sets[@]}" >"$run_dir/logs/learner.log" 2>&1 &
pids+=($!)
if ((port == 0)); then
  # The ports the OS chose, from the learner's first lines.
  for _ in $(seq 300); do
    join=$(grep -o "join: *tcp://127\.0\.0\.1:[0-9]*" "$run_dir/logs/learner.log" | head -n 1 | grep -o 'tcp://.*' || true)
    weights=$(grep -o "weights: *tcp://127\.0\.0\.1:[0-9]*" "$run_dir/logs/learner.log" | head -n 1 | grep -o 'tcp://.*' || true)
    [[ -n $join ]] && break
    kill -0 "${pids[0]}" 2>/dev/null || break
    sleep 0.1
  done
  [[ -n $join ]] || die "the learner did not report its join endpoint; see $run_dir/logs/learner.log"
fi
for ((i = 0; i < shards; i++)); do
  "$bin" replay --join "$join" --insert-bind "tcp://127.0.0.1:0" --sample-bind "tcp://127.0.0.1:0" \
    --snapshot "$run_dir/shard-$i.replay" "${peer_curve[@]}" >"$run_dir/logs/shard-$i.log" 2>&1 &
  pids+=($!)
done
# No --seed: each actor seeds its own random streams (episode starts, exploration) from the run's
# seed mixed with the index the learner gives it, so they follow --set seed=S as the learner does.
for ((i = 0; i < actors; i++)); do
  "$bin" actor --join "$join" "${peer_curve[@]}" >"$run_dir/logs/actor-$i.log" 2>&1 &
  pids+=($!)
done

# The env the run trains (env.name in its config; the built-in default is hfo), for the hint below.
config_file=$config
[[ -n $resume ]] && config_file=$run_dir/config.toml
env_name=$(awk -F'"' '/^\[/ { in_env = ($0 ~ /^\[env\]/) } in_env && /^name *=/ { print $2; exit }' "$config_file" 2>/dev/null || true)
env_name=${env_name:-hfo}

cat <<EOF
local-cluster: learner + $shards shards + $actors actors on this machine$( ((curve)) && echo ", CURVE on every socket")
  run directory: $run_dir   (config.toml, metrics.csv, episodes.csv, checkpoint.ckpt)
  logs:          $run_dir/logs/{learner,shard-*,actor-*}.log
  learner:       $join (weights on $weights)
  add an actor:  $bin actor --join $join ${peer_curve[*]}
  watch it:      $bin monitor --join $join ${peer_curve[*]}   (metrics URLs: $run_dir/metrics_urls.txt)
Ctrl-C stops everything and leaves the run resumable.
EOF
if [[ $env_name == hfo* ]]; then
  cat <<EOF
  expect:        HFO takes tens of minutes to learn: the success rate stays near 0.00 for the first
                 minutes (fast.toml on two cores: a training goal rate near .90 after 10-15 minutes).
                 A task learned in seconds: $bin train --config deploy/configs/reach_stop.toml
EOF
fi

start=$(date +%s)
# --pid: when the learner exits, tail prints what it wrote last (its final line) and exits too.
tail -n +1 -F --pid="${pids[0]}" "$run_dir/logs/learner.log" 2>/dev/null &
tail_pid=$!
while kill -0 "${pids[0]}" 2>/dev/null; do
  if ((duration > 0 && $(date +%s) - start >= duration)); then
    break
  fi
  sleep 1
done
if ! kill -0 "${pids[0]}" 2>/dev/null; then
  wait "${pids[0]}" && status=0 || status=$?
  wait "$tail_pid" 2>/dev/null || true
  final_shown=1
  if ((status != 0)); then
    echo "local-cluster: the learner exited with status $status; see $run_dir/logs/learner.log" >&2
  fi
else
  kill "$tail_pid" 2>/dev/null || true
  wait "$tail_pid" 2>/dev/null || true
fi
