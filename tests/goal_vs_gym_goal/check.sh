#!/usr/bin/env bash
# Differential check of envs/goal against gym-goal's own Python code (not run by ctest: it needs
# a gym-goal checkout). Both sides play the same scripted random policy and, with the noise on,
# the same uniform draws (stubs/gym/utils/seeding.py is core/rng.hpp's xoshiro256++ in Python).
# Usage: tests/goal_vs_gym_goal/check.sh GYM_GOAL_DIR [BUILD_DIR=build] [EPISODES=300]
# GYM_GOAL_DIR: a checkout of github.com/cycraig/gym-goal (checked at 8e142be).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
gym_goal=$(cd "$1" && pwd)
build=$(cd "${2:-$root/build}" && pwd)
episodes=${3:-300}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
g++ -std=c++20 -O2 -I"$root" "$here/run_goal_env.cpp" "$build/envs/libpamdp_envs.a" "$build/core/libpamdp_core.a" \
  -o "$work/run_goal_env"
for noise in 1 0; do
  for kick in 0.7 0.97; do
    PYTHONPATH="$here/stubs:$gym_goal" python3 "$here/run_gym_goal.py" "$noise" "$episodes" "$kick" >"$work/gym.txt"
    "$work/run_goal_env" "$noise" "$episodes" "$kick" >"$work/ours.txt"
    echo -n "noise $noise, kick-to share $kick: "
    python3 "$here/compare.py" "$work/gym.txt" "$work/ours.txt" 1e-9
  done
done
