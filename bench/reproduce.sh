#!/usr/bin/env bash
# Reruns one full training and evaluation end to end and prints the paper-style table row, so
# anyone can check a results claim on their own machine:
#
#   bench/reproduce.sh [--config FILE] [--seed S] [--run-dir DIR] [--episodes N]
#                      [--checkpoint best|final] [--eval-seed E] [--set key=value ...]
#
# Trains with `pamdp train` (default deploy/configs/fast.toml, seed 1, run directory
# runs/reproduce-<config>-seed<S>; an existing one is resumed), evaluates the best greedy
# checkpoint (best.ckpt, else checkpoint.ckpt; --checkpoint final: the final policy,
# checkpoint.ckpt, MP-DQN's protocol) on N episodes (default 100, the paper's protocol) with
# `pamdp eval --seed E` (default 1; docs/results.md scores final policies with 7), and prints:
#
#   config, seed, updates, episodes, wall-clock, first update/hour at which the goal rate over
#   the last 100 training episodes reached .90 and .96, scoring rate, average steps to goal,
#   mean return (Platform's measure).
#
# Builds build/bin/pamdp first if it is missing (PAMDP_BIN=path/to/pamdp runs another build).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

config=deploy/configs/fast.toml
seed=1
run_dir=""
episodes=100
which=best
eval_seed=1
sets=()

usage() { sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "reproduce: $*" >&2; exit 2; }
need_value() { [[ $# -ge 2 && -n $2 ]] || die "$1 needs a value (see --help)"; }

while [[ $# -gt 0 ]]; do
  case $1 in
    --config) need_value "$@"; config=$2; shift 2 ;;
    --seed) need_value "$@"; seed=$2; shift 2 ;;
    --run-dir) need_value "$@"; run_dir=$2; shift 2 ;;
    --episodes) need_value "$@"; episodes=$2; shift 2 ;;
    --checkpoint) need_value "$@"; which=$2; shift 2 ;;
    --eval-seed) need_value "$@"; eval_seed=$2; shift 2 ;;
    --set) need_value "$@"; sets+=(--set "$2"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
[[ -f $config ]] || die "no config file '$config' (presets are in deploy/configs/)"
[[ $seed =~ ^[0-9]+$ ]] || die "--seed must be a non-negative integer, not '$seed'"
[[ $episodes =~ ^[1-9][0-9]*$ ]] || die "--episodes must be a positive integer, not '$episodes'"
[[ $which == best || $which == final ]] || die "--checkpoint takes best or final, not '$which'"
[[ $eval_seed =~ ^[0-9]+$ ]] || die "--eval-seed must be a non-negative integer, not '$eval_seed'"

bin=${PAMDP_BIN:-build/bin/pamdp}
if [[ ! -x $bin ]]; then
  echo "reproduce: building $bin (tests/run.sh builds and tests everything)" >&2
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  ninja -C build bin/pamdp >/dev/null
fi
name=$(basename "$config" .toml)
run_dir=${run_dir:-runs/reproduce-$name-seed$seed}

if [[ -f $run_dir/checkpoint.ckpt ]]; then
  echo "reproduce: resuming $run_dir" >&2
  "$bin" train --resume "$run_dir" "${sets[@]}"
else
  "$bin" train --config "$config" --seed "$seed" --run-dir "$run_dir" "${sets[@]}"
fi

checkpoint=$run_dir/checkpoint.ckpt
[[ $which == best && -f $run_dir/best.ckpt ]] && checkpoint=$run_dir/best.ckpt
result=$("$bin" eval --checkpoint "$checkpoint" --episodes "$episodes" --seed "$eval_seed" --json | tail -n 1)

# The first metrics row at which the training goal rate (last 100 episodes) reached a level.
first_reach() {
  awk -F, -v level="$1" '
    NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    $col["success_rate_100"] >= level && $col["episodes"] >= 100 {
      printf "%d / %.2f h", $col["updates"], $col["wall_seconds"] / 3600; found = 1; exit
    }
    END { if (!found) print "not reached" }' "$run_dir/metrics.csv"
}
last_row() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    { u = $col["updates"]; e = $col["episodes"]; w = $col["wall_seconds"] }
    END { printf "%d %d %.2f", u, e, w / 3600 }' "$run_dir/metrics.csv"
}
read -r updates train_episodes hours <<<"$(last_row)"
json_field() { sed -E "s/.*\"$1\":([^,}]*).*/\1/" <<<"$result"; }

printf '\n| config | seed | updates | episodes | wall-clock (h) | .90 reached (updates / h) | .96 reached | scoring (%s ep, %s) | avg steps to goal | mean return |\n' "$episodes" "$which"
printf '| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n'
printf '| %s | %s | %s | %s | %s | %s | %s | %.3f | %.1f | %.3f |\n' "$name" "$seed" "$updates" "$train_episodes" "$hours" \
  "$(first_reach 0.90)" "$(first_reach 0.96)" "$(json_field goal_rate)" "$(json_field avg_steps_to_goal)" \
  "$(json_field avg_return)"
echo "$result"
