#!/usr/bin/env bash
# Builds with AddressSanitizer + UndefinedBehaviorSanitizer into build-asan/ and runs ctest.
# Not part of CI (too slow for 2 cores); run it before landing changes to hot paths.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
deploy/install-deps.sh
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPAMDP_SANITIZE=ON -DPAMDP_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j "$(nproc 2>/dev/null || echo 2)"
cd build-asan
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" "$@"
