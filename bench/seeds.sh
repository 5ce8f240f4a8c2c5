#!/usr/bin/env bash
# Trains and evaluates several seeds of one config (bench/reproduce.sh for each, a few at a time)
# and prints one table row per seed plus a verdict against a scoring / steps target:
#
#   bench/seeds.sh [--config FILE] [--seeds 1,2,3,4,5] [--jobs 2] [--episodes N]
#                  [--checkpoint best|final] [--target-rate R] [--target-steps S] [--out DIR]
#                  [--eval-seed E] [--set key=value ...]
#
# Defaults: deploy/configs/fast.toml, seeds 1-5, 2 at a time (one per core), evaluation on 1,000
# episodes of best.ckpt (--checkpoint final: of the final policy, MP-DQN's protocol, as for the
# presets deploy/configs/<task>-<learner>.toml) with `pamdp eval --seed 1` (--eval-seed E: with
# seed E; docs/results.md scores final policies with 7), target: scoring >= .99 with <= 80
# average steps to goal (issue 7); the mean scoring and mean return over the seeds follow the
# rows. Run directories are DIR/seedS (default DIR runs/seeds-<config>; an existing one is
# resumed) with each seed's log beside it. Exit status 0 whether or not the target is met; 2 on
# a usage error, 1 when a seed's training or evaluation failed (its log says why).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

config=deploy/configs/fast.toml
seeds=1,2,3,4,5
jobs=2
episodes=1000
which=best
eval_seed=1
target_rate=0.99
target_steps=80
out=""
sets=()

usage() { sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "seeds: $*" >&2; exit 2; }
need_value() { [[ $# -ge 2 && -n $2 ]] || die "$1 needs a value (see --help)"; }

while [[ $# -gt 0 ]]; do
  case $1 in
    --config) need_value "$@"; config=$2; shift 2 ;;
    --seeds) need_value "$@"; seeds=$2; shift 2 ;;
    --jobs) need_value "$@"; jobs=$2; shift 2 ;;
    --episodes) need_value "$@"; episodes=$2; shift 2 ;;
    --checkpoint) need_value "$@"; which=$2; shift 2 ;;
    --eval-seed) need_value "$@"; eval_seed=$2; shift 2 ;;
    --target-rate) need_value "$@"; target_rate=$2; shift 2 ;;
    --target-steps) need_value "$@"; target_steps=$2; shift 2 ;;
    --out) need_value "$@"; out=$2; shift 2 ;;
    --set) need_value "$@"; sets+=(--set "$2"); shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
[[ -f $config ]] || die "no config file '$config' (presets are in deploy/configs/)"
[[ $seeds =~ ^[0-9]+(,[0-9]+)*$ ]] || die "--seeds takes a comma-separated list of integers, e.g. 1,2,3, not '$seeds'"
[[ $jobs =~ ^[1-9][0-9]*$ ]] || die "--jobs must be a positive integer, not '$jobs'"
[[ $episodes =~ ^[1-9][0-9]*$ ]] || die "--episodes must be a positive integer, not '$episodes'"
[[ $which == best || $which == final ]] || die "--checkpoint takes best or final, not '$which'"
[[ $eval_seed =~ ^[0-9]+$ ]] || die "--eval-seed must be a non-negative integer, not '$eval_seed'"
[[ $target_rate =~ ^(0(\.[0-9]+)?|1(\.0+)?)$ ]] || die "--target-rate must be in [0, 1], not '$target_rate'"
[[ $target_steps =~ ^[0-9]+(\.[0-9]+)?$ ]] || die "--target-steps must be a non-negative number, not '$target_steps'"

name=$(basename "$config" .toml)
out=${out:-runs/seeds-$name}
mkdir -p "$out"
IFS=, read -r -a seed_list <<<"$seeds"

pids=()
for seed in "${seed_list[@]}"; do
  while [[ $(jobs -rp | wc -l) -ge $jobs ]]; do
    wait -n || true
  done
  echo "seeds: training seed $seed (log $out/seed$seed.log)" >&2
  bash bench/reproduce.sh --config "$config" --seed "$seed" --run-dir "$out/seed$seed" --episodes "$episodes" \
    --checkpoint "$which" --eval-seed "$eval_seed" "${sets[@]}" >"$out/seed$seed.log" 2>&1 &
  pids+=($!)
done
failed=0
for i in "${!pids[@]}"; do
  if ! wait "${pids[$i]}"; then
    echo "seeds: seed ${seed_list[$i]} failed; see $out/seed${seed_list[$i]}.log" >&2
    failed=1
  fi
done

# Each log ends with reproduce.sh's header, separator, row and JSON: the table takes the header
# and separator from the first log that has them, and the JSON gives the verdict.
echo
for seed in "${seed_list[@]}"; do
  if header=$(grep -m 1 -A 1 '^| config |' "$out/seed$seed.log"); then
    echo "$header"
    break
  fi
done
met=0
ran=0
sum_rate=0
sum_return=0
for seed in "${seed_list[@]}"; do
  log=$out/seed$seed.log
  row=$(grep -E "^\| $name \| $seed \|" "$log" | tail -n 1 || true)
  json=$(tail -n 1 "$log")
  if [[ -z $row || $json != \{* ]]; then
    printf '| %s | %s | failed: see %s |\n' "$name" "$seed" "$log"
    continue
  fi
  echo "$row"
  ran=$((ran + 1))
  rate=$(sed -E 's/.*"goal_rate":([^,}]*).*/\1/' <<<"$json")
  steps=$(sed -E 's/.*"avg_steps_to_goal":([^,}]*).*/\1/' <<<"$json")
  ret=$(sed -E 's/.*"avg_return":([^,}]*).*/\1/' <<<"$json")
  sum_rate=$(awk -v a="$sum_rate" -v b="$rate" 'BEGIN { print a + b }')
  sum_return=$(awk -v a="$sum_return" -v b="$ret" 'BEGIN { print a + b }')
  if awk -v r="$rate" -v s="$steps" -v tr="$target_rate" -v ts="$target_steps" 'BEGIN { exit !(r >= tr && s <= ts) }'; then
    met=$((met + 1))
  fi
done
if ((ran > 0)); then
  awk -v r="$sum_rate" -v g="$sum_return" -v n="$ran" -v w="$which" \
    'BEGIN { printf "\nmean over %d seeds (%s checkpoints): scoring %.3f, return %.3f\n", n, w, r / n, g / n }'
fi
printf '\n%d of %d seeds reached scoring >= %s with <= %s steps to goal (%d episodes each)\n' \
  "$met" "${#seed_list[@]}" "$target_rate" "$target_steps" "$episodes"
[[ $ran -eq ${#seed_list[@]} && $failed -eq 0 ]] || exit 1
