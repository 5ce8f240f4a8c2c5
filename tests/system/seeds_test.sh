#!/usr/bin/env bash
# bench/seeds.sh end to end on the toy task: two seeds trained side by side, evaluated, one table
# row each, and the verdict counts them (ReachStop is solved by every seed in ~1 s); a target no
# agent can meet is counted as missed; --eval-seed scores with that evaluation seed; bad --seeds and
# --eval-seed values are refused by name.
#   seeds_test.sh PAMDP_BIN SOURCE_DIR
set -euo pipefail
bin=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

out=$(PAMDP_BIN=$bin bash "$src/bench/seeds.sh" --config "$src/deploy/configs/reach_stop.toml" --seeds 1,2 \
  --episodes 200 --target-rate 0.9 --target-steps 100 --out "$work/a" 2>"$work/a.err") || fail "seeds.sh failed: $out $(cat "$work/a.err")"
echo "$out"
[[ $(grep -cE '^\| reach_stop \| [12] \|' <<<"$out") -eq 2 ]] || fail "expected one row per seed"
grep -q '^2 of 2 seeds reached scoring >= 0.9 with <= 100 steps' <<<"$out" || fail "verdict should count both seeds"
[[ -f $work/a/seed1/best.ckpt || -f $work/a/seed1/checkpoint.ckpt ]] || fail "no checkpoint in the seed's run directory"

# The same runs (resumed, nothing left to train) against a target of under one step: none meets it.
out=$(PAMDP_BIN=$bin bash "$src/bench/seeds.sh" --config "$src/deploy/configs/reach_stop.toml" --seeds 1,2 \
  --episodes 200 --target-rate 0.9 --target-steps 0.5 --out "$work/a" 2>/dev/null) || fail "rerun failed: $out"
grep -q '^0 of 2 seeds reached' <<<"$out" || fail "an unreachable target must be counted as missed: $out"

# MP-DQN's protocol: the final policies, with the mean return over the seeds after the rows.
out=$(PAMDP_BIN=$bin bash "$src/bench/seeds.sh" --config "$src/deploy/configs/reach_stop.toml" --seeds 1,2 \
  --episodes 200 --checkpoint final --out "$work/a" 2>/dev/null) || fail "--checkpoint final failed: $out"
grep -q '^| config | .*scoring (200 ep, final) .*| mean return |' <<<"$out" || fail "no final-policy header: $out"
# (The final policies' mean is not held to .9: DDPG's last snapshot swings, .705 for seed 1 on an
# AVX2 machine; the best checkpoints above are.)
grep -qE '^mean over 2 seeds \(final checkpoints\): scoring (0\.[5-9][0-9]*|1\.000), return ' <<<"$out" ||
  fail "no mean over the seeds: $out"

# --eval-seed: the row and JSON of each seed are `pamdp eval --seed E` of its checkpoint.
out=$(PAMDP_BIN=$bin bash "$src/bench/seeds.sh" --config "$src/deploy/configs/reach_stop.toml" --seeds 1,2 \
  --episodes 200 --checkpoint final --eval-seed 7 --out "$work/a" 2>/dev/null) || fail "--eval-seed 7 failed: $out"
want=$("$bin" eval --checkpoint "$work/a/seed1/checkpoint.ckpt" --episodes 200 --seed 7 --json 2>/dev/null | tail -n 1)
[[ $(tail -n 1 "$work/a/seed1.log") == "$want" ]] ||
  fail "seed 1 was not scored with eval --seed 7: $(tail -n 1 "$work/a/seed1.log") against $want"
if err=$(bash "$src/bench/seeds.sh" --eval-seed x 2>&1); then
  fail "--eval-seed x accepted"
fi
grep -q -- "--eval-seed" <<<"$err" || fail "the error does not name --eval-seed: $err"

if err=$(bash "$src/bench/seeds.sh" --checkpoint last 2>&1); then
  fail "--checkpoint last accepted"
fi
grep -q -- "--checkpoint" <<<"$err" || fail "the error does not name --checkpoint: $err"

if err=$(bash "$src/bench/seeds.sh" --seeds 1,x 2>&1); then
  fail "--seeds 1,x accepted"
fi
grep -q -- "--seeds" <<<"$err" || fail "the error does not name --seeds: $err"
echo "seeds_test: ok"
