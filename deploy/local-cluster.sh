#!/usr/bin/env bash
# Runs the main job on this machine with the embedded simulator.
#
# For now (until the distributed actor-learner system lands) the main job is the paper's
# evaluation protocol played by the scripted offense baseline: 100 episodes of 1v0 HFO,
# printing the paper's table row. Extra arguments go to `pamdp eval`
# (e.g. --episodes 1000 --seed 7 --json, or --policy random).
# Builds build/bin/pamdp first if it is missing, installing the Debian packages it needs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

if [[ ! -x build/bin/pamdp ]]; then
  echo "local-cluster: building build/bin/pamdp (first run)..." >&2
  deploy/install-deps.sh
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build --target pamdp -j "$(nproc 2>/dev/null || echo 2)" >/dev/null
fi

echo "local-cluster: scripted offense baseline, paper protocol (100 episodes, embedded HFO 1v0)" >&2
exec build/bin/pamdp eval --policy scripted --episodes 100 "$@"
