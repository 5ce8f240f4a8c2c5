#!/usr/bin/env bash
# Operator errors: each must end the process with a non-zero status and one clear error line that
# names the problem and the fix, within a bounded time:
#   bad flag, unknown config key (the valid keys listed), value out of range, unreachable join
#   address (actor and shard, short --join-timeout), learner port in use, corrupt checkpoint
#   (truncated; bytes flipped) for --resume and eval --checkpoint, a run directory of another
#   experiment (--resume with other network widths), a cluster socket beyond loopback without CURVE
#   or insecure mode (and insecure mode's gauge and warning, in a network namespace of its own).
# Usage: tests/system/operator_errors_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
bin=${1:?path to pamdp}
src=${2:?source dir}
work=$(mktemp -d /tmp/pamdp-operator-test.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  if [[ ${keep:-0} == 1 ]]; then echo "kept $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT
failures=0
cases=0
config=$src/deploy/configs/reach_stop.toml

# expect_error NAME TIMEOUT_S PATTERN... -- COMMAND...: COMMAND must exit with status 2 (pamdp
# --help's "an error you can fix") within TIMEOUT_S, and one line of its stderr, starting
# "pamdp: error: ", must match every PATTERN (grep -E, case-insensitive).
expect_error() {
  local name=$1 limit=$2
  shift 2
  local patterns=()
  while [[ $1 != -- ]]; do
    patterns+=("$1")
    shift
  done
  shift
  cases=$((cases + 1))
  local out=$work/$cases.err status=0 start=$SECONDS
  timeout "$limit" "$@" >"$work/$cases.out" 2>"$out" </dev/null || status=$?
  local took=$((SECONDS - start))
  local lines
  lines=$(grep '^pamdp: error: ' "$out" || true)
  for p in "${patterns[@]}"; do
    lines=$(grep -iE -- "$p" <<<"$lines" || true)
  done
  local error_lines
  error_lines=$(grep -ciE 'error|fatal' "$out" || true)
  if ((status != 2)) || [[ -z $lines ]]; then
    failures=$((failures + 1))
    echo "FAIL  $name: status $status after ${took}s; stderr:" >&2
    sed 's/^/      /' "$out" | head -n 12 >&2
    return 0
  fi
  printf 'ok    %-34s status %d, %ds, %d error line(s): %s\n' "$name" "$status" "$took" "$error_lines" "$(head -n 1 <<<"$lines" | cut -c1-220)"
}

# --- flags and config -------------------------------------------------------------------------
expect_error "bad flag" 10 "--no-such-flag" -- "$bin" learner --no-such-flag
expect_error "bad subcommand" 10 "unknown subcommand 'lerner'" "valid:" -- "$bin" lerner
expect_error "unknown config key" 10 "ddpg.gama" "gamma" -- \
  "$bin" train --config "$config" --set ddpg.gama=0.9 --run-dir "$work/unused-1"
expect_error "config value out of range" 10 "ddpg.gamma" "within" -- \
  "$bin" train --config "$config" --set ddpg.gamma=2 --run-dir "$work/unused-2"
printf '[ddpg]\nhidden = [64, 64]\nbatch_sise = 32\n' >"$work/bad.toml"
expect_error "unknown key in a config file" 10 "batch_sise" "batch_size" -- \
  "$bin" train --config "$work/bad.toml" --run-dir "$work/unused-3"
expect_error "missing config file" 10 "nope.toml" -- "$bin" train --config "$work/nope.toml" --run-dir "$work/unused-4"

# --- unreachable learner ----------------------------------------------------------------------
expect_error "actor: unreachable --join" 20 "tcp://127.0.0.1:1" "--join" -- \
  "$bin" actor --join tcp://127.0.0.1:1 --join-timeout 2
expect_error "replay: unreachable --join" 20 "tcp://127.0.0.1:1" "--join" -- \
  "$bin" replay --join tcp://127.0.0.1:1 --join-timeout 2

# --- secure by default (issue 33): no cluster socket beyond loopback without CURVE or insecure ---
# Refused before anything binds or connects (0.0.0.0 as a join target would reach this machine only).
expect_error "learner: wildcard bind without CURVE" 10 "cluster.learner_bind" "pamdp keygen" "cluster.curve=true" \
  "cluster.insecure=true" -- "$bin" learner --config "$config" --run-dir "$work/exposed" \
  --set cluster.learner_bind=tcp://0.0.0.0:0 --set cluster.weights_bind=tcp://127.0.0.1:0
[[ ! -e $work/exposed ]] || { failures=$((failures + 1)); echo "FAIL  a refused learner created its run directory" >&2; }
expect_error "learner: weights bind without CURVE" 10 "cluster.weights_bind" "pamdp keygen" -- \
  "$bin" learner --config "$config" --run-dir "$work/exposed" --set cluster.learner_bind=tcp://127.0.0.1:0 \
  --set "cluster.weights_bind=tcp://*:0"
expect_error "learner: advertise host, loopback binds" 10 "cluster.advertise_host" "loopback" -- \
  "$bin" learner --config "$config" --run-dir "$work/exposed" --set cluster.advertise_host=10.0.0.5
expect_error "replay: wildcard bind without CURVE" 10 "--insert-bind" "pamdp keygen" "--curve-keys" "--insecure" -- \
  "$bin" replay --join tcp://127.0.0.1:1 --insert-bind "tcp://*:0" --join-timeout 2
expect_error "replay: learner beyond loopback" 10 "--join" "--insecure" -- \
  "$bin" replay --join tcp://0.0.0.0:1 --join-timeout 2
expect_error "actor: learner beyond loopback" 10 "--join" "pamdp keygen" "--curve-keys" "--insecure" -- \
  "$bin" actor --join tcp://0.0.0.0:1 --join-timeout 2

# With cluster.insecure = true the learner starts on a wildcard bind, warns once and exports
# pamdp_security_insecure 1. Run in a network namespace of its own (only lo), so that the wildcard
# bind reaches nothing else; skipped where unshare -n is not permitted.
if command -v unshare >/dev/null && unshare -n true 2>/dev/null; then
  cases=$((cases + 1))
  unshare -n bash -c '
    ip link set lo up
    "$1" learner --config "$2" --run-dir "$3/insecure" --set cluster.learner_bind=tcp://0.0.0.0:0 \
      --set cluster.weights_bind=tcp://0.0.0.0:0 --set cluster.insecure=true --set train.max_updates=1 \
      >"$3/insecure.log" 2>&1 &
    learner=$!
    url=""
    for _ in $(seq 100); do
      url=$(grep -o "http://127\.0\.0\.1:[0-9]*/metrics" "$3/insecure.log" | head -n 1 || true)
      [[ -n $url ]] && break
      sleep 0.1
    done
    curl -sf --max-time 2 "$url" | grep "^pamdp_security_insecure " >"$3/insecure.gauge" || true
    kill -TERM $learner; wait $learner || true' _ "$bin" "$config" "$work"
  gauge=$(cat "$work/insecure.gauge" 2>/dev/null || true)
  warnings=$(grep -c "INSECURE" "$work/insecure.log" || true)
  if [[ $gauge == "pamdp_security_insecure 1" && $warnings == 1 ]]; then
    printf 'ok    %-34s %s, %d warning line\n' "learner: cluster.insecure = true" "$gauge" "$warnings"
  else
    failures=$((failures + 1))
    echo "FAIL  learner: cluster.insecure = true: gauge '$gauge', $warnings INSECURE warning(s); log:" >&2
    tail -n 8 "$work/insecure.log" >&2
  fi
else
  echo "skip  learner: cluster.insecure = true (unshare -n not permitted here)"
fi

# --- a port in use ----------------------------------------------------------------------------
python3 -c '
import socket, sys, time
s = socket.socket(); s.bind(("127.0.0.1", 0)); s.listen(1)
print(s.getsockname()[1], flush=True)
time.sleep(120)' >"$work/port" &
pids+=($!)
for _ in $(seq 100); do [[ -s $work/port ]] && break; sleep 0.1; done
port=$(cat "$work/port")
expect_error "learner: join port in use" 20 "$port" "in use|already" -- \
  "$bin" learner --config "$config" --run-dir "$work/busy" --set "cluster.learner_bind=tcp://127.0.0.1:$port" \
  --set cluster.weights_bind=tcp://127.0.0.1:0
expect_error "learner: metrics port in use" 20 "$port" "in use|already" -- \
  "$bin" learner --config "$config" --run-dir "$work/busy-metrics" --set cluster.learner_bind=tcp://127.0.0.1:0 \
  --set cluster.weights_bind=tcp://127.0.0.1:0 --metrics-port "$port"

# --- corrupt checkpoints ----------------------------------------------------------------------
"$bin" train --config "$config" --run-dir "$work/run" --set train.max_updates=200 --set replay.warmup=100 \
  --set train.eval_every_updates=0 --set ddpg.hidden=[16,16] >"$work/train.log" 2>&1 ||
  { echo "FAIL  could not make a run to corrupt:"; tail "$work/train.log"; exit 1; }
ckpt=$work/run/checkpoint.ckpt
size=$(stat -c %s "$ckpt")
cp -r "$work/run" "$work/truncated"
truncate -s $((size / 2)) "$work/truncated/checkpoint.ckpt"
expect_error "resume: truncated checkpoint" 20 "checkpoint.ckpt" "corrupt|truncated" -- "$bin" train --resume "$work/truncated"
expect_error "eval: truncated checkpoint" 20 "checkpoint.ckpt" "corrupt|truncated" -- \
  "$bin" eval --checkpoint "$work/truncated/checkpoint.ckpt" --episodes 2
# Bytes flipped in the middle (the network parameters): the loader must notice.
cp -r "$work/run" "$work/flipped"
python3 - "$work/flipped/checkpoint.ckpt" <<'EOF'
import sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
for i in range(len(b) // 2, len(b) // 2 + 16):
    b[i] ^= 0x5A
open(p, "wb").write(bytes(b))
EOF
expect_error "resume: flipped bytes" 20 "checkpoint.ckpt" "corrupt" -- "$bin" train --resume "$work/flipped"
expect_error "eval: flipped bytes" 20 "checkpoint.ckpt" "corrupt" -- \
  "$bin" eval --checkpoint "$work/flipped/checkpoint.ckpt" --episodes 2
head -c 4096 /dev/urandom >"$work/random.ckpt"
expect_error "eval: not a checkpoint" 20 "random.ckpt" "not a pamdp checkpoint" -- \
  "$bin" eval --checkpoint "$work/random.ckpt" --episodes 2
expect_error "resume: missing run directory" 20 "nowhere" -- "$bin" train --resume "$work/nowhere"

# --- a run directory of another experiment ----------------------------------------------------
expect_error "resume with other widths" 20 "checkpoint" "values|widths" -- \
  "$bin" train --resume "$work/run" --set ddpg.hidden=[32,32]
expect_error "learner resume with other widths" 20 "checkpoint" "values|widths" -- \
  "$bin" learner --resume "$work/run" --set ddpg.hidden=[32,32] --set cluster.learner_bind=tcp://127.0.0.1:0 \
  --set cluster.weights_bind=tcp://127.0.0.1:0
expect_error "new run in a used run directory" 20 "already holds a run" "--resume" -- \
  "$bin" train --config "$config" --run-dir "$work/run"

if ((failures > 0)); then
  keep=1
  echo "operator_errors_test: FAIL: $failures of $cases cases" >&2
  exit 1
fi
echo "operator_errors_test: OK: $cases cases"
