#!/usr/bin/env bash
# deploy/Dockerfile for real: builds the image on a Debian 12 base, runs `pamdp eval --policy
# scripted` in it, then a cluster of containers (a learner, a replay shard and two actors, each its
# own container, --network host on loopback, CURVE with keys from `pamdp keygen` run in the image)
# that must train with every peer joined and stop cleanly on `docker stop` (exit status 0, the
# checkpoint and the shard's snapshot written). Prints the image's size.
#   Docker: the one `docker info` reaches, or else a dockerd this test starts and stops
#   (--bridge=none --iptables=false, its own socket; data root PAMDP_DOCKER_ROOT, default
#   /var/lib/pamdp-test-docker, kept so that the base image and the build cache are reused).
#   Base: PAMDP_BASE_IMAGE if set (e.g. debian:12 where a registry is reachable); otherwise
#   pamdp-base:bookworm, made once with debootstrap (minbase, from this machine's Debian mirror)
#   and `docker import`, with apt's lists and caches, docs, man pages and locales left out.
# Heavy (minutes to build the image the first time): not in the default ctest run; register it
# with -DPAMDP_CONTAINER_TEST=ON (ctest -L container) or run it directly. Skips (77) without
# Docker or root.
# Usage: tests/system/container_test.sh PATH/TO/pamdp SOURCE_DIR
set -euo pipefail
src=$(cd "${2:?source dir}" && pwd)  # $1 (the host's pamdp) is unused: the image builds its own
test_name=container_test
skip() {
  echo "$test_name: SKIP: $*"
  exit 77
}
command -v docker >/dev/null || skip "no docker client (Debian: apt-get install docker.io)"
[[ $(id -u) == 0 ]] || skip "needs root"

work=$(mktemp -d "/tmp/pamdp-$test_name.XXXXXX")
containers=()
dockerd_pid=""
cleanup() {
  local status=$?
  if ((${#containers[@]})); then docker rm -f "${containers[@]}" >/dev/null 2>&1 || true; fi
  if [[ -n $dockerd_pid ]]; then
    kill -TERM "$dockerd_pid" 2>/dev/null || true
    for _ in $(seq 100); do kill -0 "$dockerd_pid" 2>/dev/null || break; sleep 0.2; done
    # dockerd leaves its default network namespace mounted under its exec root.
    if mountpoint -q "$work/exec/netns/default" 2>/dev/null; then umount "$work/exec/netns/default" || true; fi
  fi
  if [[ ${keep:-0} == 1 ]]; then echo "kept $work"; else rm -rf "$work" || true; fi
  exit "$status"
}
trap cleanup EXIT
fail() {
  echo "$test_name: FAIL: $*" >&2
  for c in "${containers[@]}"; do
    echo "--- docker logs $c" >&2
    docker logs --tail 15 "$c" >&2 2>&1 || true
  done
  keep=1
  exit 1
}
t0=$(date +%s.%N)
since() { awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1fs", b - a }'; }
wait_for() {
  local seconds=$1 what=$2
  shift 2
  local deadline=$(($(date +%s) + seconds))
  until eval "$*"; do
    (($(date +%s) < deadline)) || fail "$(eval "echo \"$what\"") (not within ${seconds}s)"
    sleep 0.5
  done
}
gt() { awk -v a="${1:-}" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 > b + 0) }'; }
metric() {
  curl -sf --max-time 2 "$1" 2>/dev/null |
    awk -v name="$2" -v labels="${3:-}" '$1 == name || (index($1, name "{") == 1 && index($1, labels) > 0) { print $2; exit }' || true
}

# --- a Docker engine ---------------------------------------------------------------------------
if ! docker info >/dev/null 2>&1; then
  command -v dockerd >/dev/null || skip "no Docker engine reachable and no dockerd to start"
  root=${PAMDP_DOCKER_ROOT:-/var/lib/pamdp-test-docker}
  mkdir -p "$root" "$work/exec"
  export DOCKER_HOST=unix://$work/docker.sock
  dockerd --data-root "$root" --exec-root "$work/exec" --pidfile "$work/dockerd.pid" --host "$DOCKER_HOST" \
    --bridge=none --iptables=false --ip6tables=false >"$work/dockerd.log" 2>&1 &
  dockerd_pid=$!
  wait_for 60 'dockerd did not answer: $(tail -n 3 "$work/dockerd.log")' 'docker info >/dev/null 2>&1'
  echo "dockerd started at $(since) (data root $root)"
fi

# --- the base image ---------------------------------------------------------------------------
base=${PAMDP_BASE_IMAGE:-pamdp-base:bookworm}
if ! docker image inspect "$base" >/dev/null 2>&1; then
  [[ $base == pamdp-base:bookworm ]] || fail "no image $base (unset PAMDP_BASE_IMAGE to make one with debootstrap)"
  if ! command -v debootstrap >/dev/null; then
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap; } >/dev/null 2>&1 ||
      skip "no base image and no debootstrap to make one"
  fi
  mirror=$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list 2>/dev/null |
    grep -oE 'https?://[^ ]+/debian/?( |$)' | grep -v security | head -n 1 | tr -d ' ' || true)
  mirror=${mirror:-http://deb.debian.org/debian}
  echo "making $base: debootstrap bookworm from $mirror"
  debootstrap --variant=minbase bookworm "$work/rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 ||
    fail "debootstrap failed: $(tail -n 3 "$work/debootstrap.log")"
  rm -rf "$work"/rootfs/var/cache/apt/* "$work"/rootfs/var/lib/apt/lists/* "$work"/rootfs/usr/share/{doc,man,locale}/*
  tar -C "$work/rootfs" -c . | docker import - "$base" >/dev/null
  rm -rf "$work/rootfs"
  echo "made $base at $(since): $(docker image inspect -f '{{.Size}}' "$base" | awk '{ printf "%.0f MB", $1 / 1e6 }')"
fi

# --- the image ---------------------------------------------------------------------------------
image=pamdp:container-test
build_start=$(date +%s)
docker build --network host --build-arg "BASE=$base" -f "$src/deploy/Dockerfile" -t "$image" "$src" \
  >"$work/build.log" 2>&1 || { tail -n 30 "$work/build.log" >&2; fail "docker build failed"; }
size=$(docker image inspect -f '{{.Size}}' "$image")
base_size=$(docker image inspect -f '{{.Size}}' "$base")
echo "built $image in $(($(date +%s) - build_start)) s: $(awk -v s="$size" -v b="$base_size" \
  'BEGIN { printf "%.0f MB (base %.0f MB, pamdp and its libraries %.0f MB)", s / 1e6, b / 1e6, (s - b) / 1e6 }')"

# --- one command in it --------------------------------------------------------------------------
out=$(docker run --rm --network none "$image" eval --policy scripted --episodes 200 --seed 1 --json 2>&1) ||
  fail "pamdp eval --policy scripted failed in the image: $out"
goal_rate=$(tail -n 1 <<<"$out" | grep -o '"goal_rate": *[0-9.]*' | grep -o '[0-9.]*$' || true)
gt "$goal_rate" 0.5 || fail "the scripted policy scored '$goal_rate' in the image: $out"
echo "eval --policy scripted in the image: goal rate $goal_rate on 200 episodes"

# --- a cluster of containers ---------------------------------------------------------------------
port_free() { ! ss -Htln "sport = :$1" | grep -q .; }
port=""
for _ in $(seq 50); do
  p=$((20000 + RANDOM % 30000))
  if port_free "$p" && port_free $((p + 1)); then port=$p && break; fi
done
[[ -n $port ]] || fail "no two free ports"
join=tcp://127.0.0.1:$port
mkdir -p "$work/keys" "$work/runs"
docker run --rm --network none -v "$work/keys:/keys" "$image" keygen --dir /keys/cluster >/dev/null ||
  fail "pamdp keygen failed in the image"
run() {  # NAME ARGS…: a detached container on the host's network with the keys and run volume
  local name=pamdp-ct-$1-$$
  shift
  docker run -d --name "$name" --network host -v "$work/keys/cluster:/keys:ro" -v "$work/runs:/runs" \
    "$image" "$@" >/dev/null || fail "docker run $name failed"
  containers+=("$name")
}
run learner learner --config /etc/pamdp/configs/fast.toml --run-dir /runs/exp \
  --set "cluster.learner_bind=$join" --set "cluster.weights_bind=tcp://127.0.0.1:$((port + 1))" \
  --set cluster.advertise_host=127.0.0.1 --set replay.shards=1 \
  --set cluster.curve=true --set cluster.curve_keys_dir=/keys \
  --set replay.warmup=500 --set train.eval_every_updates=0 --set train.log_every_seconds=0.5
run shard replay --join "$join" --insert-bind tcp://127.0.0.1:0 --sample-bind tcp://127.0.0.1:0 \
  --advertise-host 127.0.0.1 --curve-keys /keys --snapshot /runs/shard-0.replay
run actor-0 actor --join "$join" --curve-keys /keys --seed 1000
run actor-1 actor --join "$join" --curve-keys /keys --seed 1001
wait_for 60 "the learner listed no metrics URL" '[[ -s $work/runs/exp/metrics_urls.txt ]]'
lurl=$(head -n 1 "$work/runs/exp/metrics_urls.txt")
peers() { metric "$lurl" pamdp_learner_peers_connected "role=\"$1\""; }
wait_for 60 'the learner counts $(peers replay) shards and $(peers actor) actors, not 1 and 2' \
  '[[ $(peers replay) == 1 && $(peers actor) == 2 ]]'
u0=$(metric "$lurl" pamdp_updates_total)
wait_for 60 "the learner's updates stuck at \$(metric \"\$lurl\" pamdp_updates_total)" \
  "gt \"\$(metric \"\$lurl\" pamdp_updates_total)\" $((${u0%.*} + 2000))"
joined=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "actors_joined") c = i; next } { v = $c } END { print v }' \
  "$work/runs/exp/metrics.csv")
[[ $joined == 2 ]] || fail "metrics.csv logs actors_joined '$joined', not 2"
echo "cluster of 4 containers at $(since): updates $(metric "$lurl" pamdp_updates_total), 1 shard and 2 actors joined (CURVE)"

# --- docker stop -------------------------------------------------------------------------------
stop_start=$(date +%s)
docker stop "${containers[@]}" >/dev/null
for c in "${containers[@]}"; do
  status=$(docker inspect -f '{{.State.Status}} {{.State.ExitCode}}' "$c")
  [[ $status == "exited 0" ]] || fail "$c is '$status' after docker stop, not 'exited 0' (killed after the grace period?)"
done
[[ -s $work/runs/exp/checkpoint.ckpt ]] || fail "the learner wrote no checkpoint on docker stop"
[[ -s $work/runs/shard-0.replay ]] || fail "the shard wrote no snapshot on docker stop"
echo "docker stop: 4 containers exited 0 in $(($(date +%s) - stop_start)) s, checkpoint and snapshot written"
echo "$test_name: PASS in $(since); image $image $(awk -v s="$size" 'BEGIN { printf "%.0f MB", s / 1e6 }')"
