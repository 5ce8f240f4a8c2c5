#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang, ASan and UBSan into build-fuzz/, writes seed
# corpora from valid messages and files, runs each target for a bounded time and prints its
# executions and findings. Not part of CI (clang and minutes of CPU). Exits 1 if any target found
# something; the inputs are kept under build-fuzz/findings/<target>/.
# Usage: tests/fuzz.sh [seconds-per-target] [target...]   (default 60 s, every target)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
seconds=${1:-60}
shift || true
[[ $seconds =~ ^[0-9]+$ && $seconds -ge 1 ]] || { echo "fuzz.sh: seconds-per-target must be a positive integer, got '$seconds'" >&2; exit 2; }
targets=("$@")
((${#targets[@]})) || targets=(fuzz_envelope fuzz_transition_batch fuzz_checkpoint fuzz_replay_snapshot fuzz_config)
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is not installed (Debian package clang)" >&2; exit 2; }
build="build-fuzz"
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPAMDP_FUZZ=ON \
  -DPAMDP_BUILD_TESTS=OFF -DPAMDP_BUILD_BENCH=OFF -DPAMDP_CUDA=OFF -DPAMDP_NATIVE=OFF >/dev/null
ninja -C "$build" -j "$jobs" fuzz_seeds "${targets[@]}" >/dev/null
seeds=$build/seeds
rm -rf "$seeds"
"$build/bin/fuzz_seeds" "$seeds" >/dev/null
mkdir -p "$seeds/fuzz_config"
cp deploy/configs/*.toml "$seeds/fuzz_config/"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
total_findings=0
printf '%-24s %12s %10s %8s %9s\n' target executions exec/s corpus findings
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t
  findings=$build/findings/$t
  rm -rf "$findings"  # this run's findings only
  mkdir -p "$corpus" "$findings"
  [[ -d $seeds/$t ]] && cp -n "$seeds/$t"/* "$corpus/" 2>/dev/null || true
  # Inputs of past findings (fixed) stay in the corpus, so a regression shows at once.
  [[ -d fuzz/regressions/$t ]] && cp -n fuzz/regressions/"$t"/* "$corpus/" 2>/dev/null || true
  log=$build/findings/$t.log
  status=0
  "$build/bin/$t" -max_total_time="$seconds" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$findings/" "$corpus" >"$log" 2>&1 || status=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -n1 || true)
  rate=$(grep -o 'exec/s: *[0-9]*' "$log" | tail -n1 | grep -o '[0-9]*$' || true)
  found=$(find "$findings" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) | wc -l)
  if ((status != 0 && found == 0)); then
    found=1  # it stopped without an artifact (e.g. a sanitizer report in a static initializer)
  fi
  total_findings=$((total_findings + found))
  printf '%-24s %12s %10s %8s %9s\n' "$t" "${execs:-?}" "${rate:-?}" "$(find "$corpus" -type f | wc -l)" "$found"
  if ((found > 0)); then
    echo "  see $log and $findings/" >&2
    grep -m3 'ERROR\|runtime error\|deadly signal' "$log" | sed 's/^/  /' >&2 || true
  fi
done
((total_findings == 0)) || { echo "fuzz.sh: $total_findings finding(s)" >&2; exit 1; }
echo "fuzz.sh: no findings"
