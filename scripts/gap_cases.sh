#!/usr/bin/env bash
# The withheld-effect cases of the gap diagnosis, as a table: every registered effect simulated
# on the article's protocol at a small and a large size (each table at a seed of its own), then
# diagnosed with the base model (the effect withheld). Columns: effect, size, truth, its rank
# among the candidates fitted alone, how it was named, the recovered parameters, their largest
# error (relative to the departure from the neutral value), the held-out gap before, its shrink,
# the effects forward selection chose, pass (named, within 20 %, shrink >= 70 %).
# The same cases run in CI (tests/gap/withheld_test.cpp); this script does not need ctest.
# Usage: scripts/gap_cases.sh [BUILD_DIR] [OUT_DIR]   (OUT_DIR/cases.md is written too)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-${BUILD_DIR:-build}}
APP="$BUILD_DIR/apps/diagnose_gap"
[ -x "$APP" ] || { echo "gap_cases: $APP not built (run scripts/build.sh)" >&2; exit 1; }
if [ $# -ge 2 ]; then
  exec "$APP" --cases --out "$2"
fi
exec "$APP" --cases
