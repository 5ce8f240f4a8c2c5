#!/usr/bin/env bash
# The hfo-server env against real HFO servers (registered only when CMake is given -DHFO_ROOT).
# Starts HFO's bin/HFO (1v0, --fullstate, synchronous) on free ports, one server per client, and:
#   1. runs hfo_server_live_test against one (feature geometry, episode starts, reward);
#   2. runs `pamdp eval --env hfo-server --policy scripted --episodes 5 --json` against another
#      and checks the JSON line;
#   3. kills a server under a running eval: pamdp exits non-zero naming SERVER_DOWN;
#   4. asks for a server where none runs: pamdp exits non-zero within
#      env.server_connect_timeout_s saying how to start one (with python3);
#   5. starts an eval together with its server, not waiting for bin/HFO's line: the env waits;
#   6. plays a 2v1 team in one process (env.server_agents = 2): both agents of one server, in
#      lockstep, the scripted team against agent2d's goalie.
# Exits 77 (skipped) when no server can be started here: no Python with numpy (bin/HFO imports
# it), no bin/HFO or rcssserver in HFO_ROOT, or the server never waits for its agent.
#
#   tests/hfo_server_integration_test.sh PAMDP_BIN LIVE_TEST_BIN HFO_ROOT
set -euo pipefail
bin=$1
live=$2
hfo_root=$(cd "$3" && pwd)
work=$(mktemp -d)
cd "$work"  # rcssserver writes its default configs into ./~/.rcssserver
groups=()
cleanup() {
  for g in "${groups[@]}"; do kill -TERM -- "-$g" 2>/dev/null || true; done
  sleep 0.5
  for g in "${groups[@]}"; do kill -KILL -- "-$g" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
skip() {
  echo "SKIP: $*" >&2
  exit 77
}
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

[[ -x $hfo_root/bin/HFO && -x $hfo_root/bin/rcssserver ]] || skip "no bin/HFO and bin/rcssserver in $hfo_root (make install in HFO's build)"
py=""
for candidate in /usr/bin/python3 python3; do  # bin/HFO: not "python" (Debian 12 has none)
  if command -v "$candidate" >/dev/null && "$candidate" -c 'import numpy' 2>/dev/null; then
    py=$candidate
    break
  fi
done
[[ -n $py ]] || skip "bin/HFO needs a Python with numpy (apt-get install python3-numpy)"

# A base port with it and the next two free (bin/HFO also takes P+1 and P+2 for its coaches).
free_port() {
  "$py" - <<'EOF'
import random, socket
for _ in range(500):
    base = random.randrange(20000, 60000)
    socks = []
    try:
        for p in (base, base + 1, base + 2):
            for kind in (socket.SOCK_DGRAM, socket.SOCK_STREAM):
                s = socket.socket(socket.AF_INET, kind)
                socks.append(s)
                s.bind(("127.0.0.1", p))
        print(base)
        break
    except OSError:
        pass
    finally:
        for s in socks:
            s.close()
EOF
}

# Starts a server in a process group of its own; sets $port. START_SERVER_ARGS: bin/HFO's flags
# beside the common ones (default: --offense-agents 1).
start_server() {
  local seed=$1
  local args=(${START_SERVER_ARGS:---offense-agents 1})
  port=$(free_port)
  [[ -n $port ]] || skip "no free port found"
  local log=$work/hfo-$port.log
  setsid "$py" "$hfo_root/bin/HFO" "${args[@]}" --headless --fullstate --no-logging --frames-per-trial 500 \
    --port "$port" --seed "$seed" >"$log" 2>&1 &
  groups+=($!)
  for _ in $(seq 1 300); do
    if grep -q "Waiting for player-controlled agent" "$log"; then
      return 0
    fi
    kill -0 "${groups[-1]}" 2>/dev/null || break
    sleep 0.2
  done
  cat "$log" >&2
  skip "the HFO server on port $port did not come up (log above)"
}

# 1. Live checks.
start_server 11
PAMDP_HFO_PORT=$port "$live" || fail "hfo_server_live_test failed against the server on port $port"

# 2. pamdp eval against a real server; the JSON line.
start_server 12
out=$("$bin" eval --env hfo-server --set "env.server_port=$port" --policy scripted --episodes 5 --seed 1 --json \
  2>"$work/eval.err") || {
  cat "$work/eval.err" >&2
  fail "pamdp eval --env hfo-server failed"
}
json=$(tail -n 1 <<<"$out")
"$py" - "$json" <<'EOF' || fail "bad JSON from pamdp eval: $json"
import json, sys
r = json.loads(sys.argv[1])
assert r["episodes"] == 5, r
assert sum(r["outcomes"].values()) == 5, r
assert set(r["outcomes"]) == {"GOAL", "CAPTURED_BY_DEFENSE", "OUT_OF_BOUNDS", "OUT_OF_TIME"}, r
assert r["goal_rate"] >= 0.8, r  # the scripted offense scores 300 of 300 on the real server
assert 30 <= r["avg_steps_to_goal"] <= 150, r
assert set(r["env_counters"]) == {"kick_power_clamped", "dash_power_clamped", "direction_wrapped"}, r
assert all(isinstance(v, int) and v >= 0 for v in r["env_counters"].values()), r
EOF
echo "eval on the real server: $json"

# 3. The server dies under a running eval.
start_server 13
server_group=${groups[-1]}
"$bin" eval --env hfo-server --set "env.server_port=$port" --policy scripted --episodes 100000 >"$work/down.out" \
  2>"$work/down.err" &
eval_pid=$!
for _ in $(seq 1 300); do  # until the agent plays (a loaded machine takes seconds to join)
  grep -q "hfo-server: joined" "$work/down.err" && break
  sleep 0.2
done
sleep 1
kill -TERM -- "-$server_group"
status=0
wait "$eval_pid" || status=$?
((status != 0)) || fail "pamdp eval went on after its server died"
grep -q "SERVER_DOWN" "$work/down.err" || {
  cat "$work/down.err" >&2
  fail "no SERVER_DOWN error after the server died"
}

# 4. No server at all.
port=$(free_port)
status=0
"$bin" eval --env hfo-server --set "env.server_port=$port" --set env.server_connect_timeout_s=2 --episodes 1 \
  >/dev/null 2>"$work/none.err" || status=$?
((status != 0)) || fail "pamdp eval succeeded without a server"
grep -q "no HFO server answers at localhost:$port (waited 2 s, env.server_connect_timeout_s)" "$work/none.err" &&
  grep -q "/usr/bin/python3 .*/bin/HFO --offense-agents 1" "$work/none.err" || {
  cat "$work/none.err" >&2
  fail "the missing server is not named, or not how to start one"
}

# 5. The agent started together with its server, before bin/HFO waits for it (the env waits).
port=$(free_port)
setsid "$py" "$hfo_root/bin/HFO" --offense-agents 1 --headless --fullstate --no-logging --frames-per-trial 500 \
  --port "$port" --seed 14 >"$work/hfo-$port.log" 2>&1 &
groups+=($!)
"$bin" eval --env hfo-server --set "env.server_port=$port" --policy scripted --episodes 3 --json >"$work/early.out" \
  2>"$work/early.err" || {
  cat "$work/early.err" "$work/hfo-$port.log" >&2
  fail "pamdp eval started together with its server failed"
}
grep -q "answered after .* giving its trainer" "$work/early.err" || fail "the env did not see the server start"

# 6. Two agents and agent2d's goalie, one process: the team env joins both, one after the other.
START_SERVER_ARGS="--offense-agents 2 --defense-npcs 1" start_server 15
out=$("$bin" eval --env hfo-server --set "env.server_port=$port" --policy scripted --offense-agents 2 --goalie \
  --episodes 20 --json 2>"$work/team.err") || {
  cat "$work/team.err" "$work/hfo-$port.log" >&2
  fail "pamdp eval of a team on one server failed"
}
json=$(tail -n 1 <<<"$out")
"$py" - "$json" <<'EOF' || fail "bad JSON from the team eval: $json"
import json, sys
r = json.loads(sys.argv[1])
assert r["episodes"] == 20, r
assert sum(r["outcomes"].values()) == 20, r
assert r["goal_rate"] >= 0.6, r  # the scripted team scores .95 against the goalie on the real server
EOF
[[ $(grep -c "hfo-server: joined localhost:$port as unum" "$work/team.err") == 2 ]] || {
  cat "$work/team.err" >&2
  fail "the team env did not join two agents"
}
echo "a team of two on the real server: $json"
echo "hfo-server integration: OK"
