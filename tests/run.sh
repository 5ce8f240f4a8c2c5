#!/usr/bin/env bash
# The project's test command: installs dependencies, configures a Release build in build/,
# builds everything, checks formatting, and runs ctest. Usage: tests/run.sh [ctest args...]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

deploy/install-deps.sh

# Formatting drift fails the run (clang-format version of the machine, .clang-format at root).
mapfile -t sources < <(git ls-files '*.cpp' '*.hpp' '*.h' 2>/dev/null || find . -path ./build -prune -o \( -name '*.cpp' -o -name '*.hpp' \) -print)
if ((${#sources[@]})); then
  if ! clang-format --dry-run --Werror "${sources[@]}" 2>/tmp/pamdp-format.log; then
    echo "tests/run.sh: formatting differs from .clang-format in:" >&2
    grep -o '^[^:]*:[0-9]*' /tmp/pamdp-format.log | sort -u | head -n 20 >&2
    echo "fix with: clang-format -i \$(git ls-files '*.cpp' '*.hpp')" >&2
    exit 1
  fi
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DPAMDP_BUILD_TESTS=ON -DPAMDP_BUILD_BENCH=ON >/dev/null
cmake --build build -j "$jobs"
cd build
ctest --output-on-failure -j "$jobs" "$@"
