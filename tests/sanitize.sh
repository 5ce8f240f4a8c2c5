#!/usr/bin/env bash
# Sanitizer builds; not part of CI (too slow for 2 cores): run them before landing changes to
# hot paths or threads.
#
#   tests/sanitize.sh [ctest args…]            AddressSanitizer + UBSan into build-asan/, all tests
#   tests/sanitize.sh --thread [gtest args…]   ThreadSanitizer into build-tsan/, the tests whose
#                                              processes run threads (metrics HTTP server, learner
#                                              and shard servers, the actor loop)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
deploy/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)

if [[ ${1:-} == --thread ]]; then
  shift
  threaded=(metrics_test learner_server_test replay_shard_test actor_loop_test)
  cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPAMDP_TSAN=ON -DPAMDP_CUDA=OFF \
    -DPAMDP_BUILD_BENCH=OFF >/dev/null
  cmake --build build-tsan -j "$jobs" --target "${threaded[@]}" pamdp
  status=0
  for t in "${threaded[@]}"; do
    echo "sanitize --thread: $t"
    PAMDP_TEST_TIME_SCALE=10 TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tests/tsan.supp" "build-tsan/bin/$t" --gtest_brief=1 "$@" || status=1
  done
  ((status == 0)) || { echo "sanitize --thread: ThreadSanitizer or a test failed (above)" >&2; exit 1; }
  echo "sanitize --thread: ${threaded[*]} clean under ThreadSanitizer"
  exit 0
fi

cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPAMDP_SANITIZE=ON -DPAMDP_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j "$jobs"
cd build-asan
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --output-on-failure -j "$jobs" "$@"
