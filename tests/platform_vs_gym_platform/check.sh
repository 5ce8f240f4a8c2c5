#!/usr/bin/env bash
# Differential check of envs/platform against gym-platform's own Python code with the noise off
# (compare.py says how). Not run by ctest: it needs a gym-platform checkout and numpy.
# Usage: tests/platform_vs_gym_platform/check.sh GYM_PLATFORM_DIR [BUILD_DIR=build] [EPISODES=400] [SEED=1]
# GYM_PLATFORM_DIR: a checkout of github.com/cycraig/gym-platform.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
[[ $# -ge 1 && -f $1/gym_platform/envs/platform_env.py ]] ||
  { echo "usage: $0 GYM_PLATFORM_DIR [BUILD_DIR] [EPISODES] [SEED] (a gym-platform checkout)" >&2; exit 2; }
gym_platform=$(cd "$1" && pwd)
build=$(cd "${2:-$root/build}" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
g++ -std=c++20 -O2 -I"$root" "$here/run_platform_env.cpp" "$build/envs/libpamdp_envs.a" "$build/core/libpamdp_core.a" \
  -o "$work/run_platform_env"
/usr/bin/python3 "$here/compare.py" "$gym_platform" "$work/run_platform_env" "${3:-400}" "${4:-1}"
