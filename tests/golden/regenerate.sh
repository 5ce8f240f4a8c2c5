#!/usr/bin/env bash
# Regenerates the golden trace(s) checked by tests/cli_test.cpp from the current simulator.
# Run it after an intended physics change, review the diff, and commit the new trace with it:
#   tests/golden/regenerate.sh [path/to/pamdp]     (default: build/bin/pamdp)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
pamdp="${1:-${here}/../../build/bin/pamdp}"
if [[ ! -x "${pamdp}" ]]; then
  echo "regenerate.sh: no pamdp binary at '${pamdp}'; build it first (ninja -C build pamdp)" >&2
  exit 1
fi

for name in kick_to_goal; do
  # The flags here must match the ones cli_test.cpp passes (GoldenTrace test).
  "${pamdp}" sim trace --init "${here}/${name}.state.json" --actions "${here}/${name}.actions.csv" \
    --no-noise >"${here}/${name}.trace.csv.tmp"
  mv "${here}/${name}.trace.csv.tmp" "${here}/${name}.trace.csv"
  echo "wrote ${here}/${name}.trace.csv ($(wc -l <"${here}/${name}.trace.csv") lines)"
done
