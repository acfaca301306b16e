#!/usr/bin/env bash
# Coverage of the safe distance out of sample: per nominal distance, the share of held-out truths
# below corrected − k·σ (the dangerous side), leaving one test point out (both emitter rows of a
# point leave together; each is predicted by a fit, residual model included, that never saw it).
# With a normal error, k = 2 promises at most 2.3 % beyond (the target: ≤ 2.5 %). p_promise says
# how likely the misses seen are under that promise, rms_z whether σ has the right size.
#   1. the article's 128 rows (config/data/paper_d455_outdoor.csv);
#   2. the simulator on the article's protocol (calibrated sensor, metrics-only path), without
#      and with a disparity offset of −0.2 px and a warm-up drift.
# Usage: bash scripts/coverage_table.sh [k]     (BUILD_DIR=build by default)
set -euo pipefail
cd "$(dirname "$0")/.."
K=${1:-2}
BIN=${BUILD_DIR:-build}/apps
for app in fit_bias simulate; do
  [ -x "$BIN/$app" ] || { echo "coverage_table: $BIN/$app not built (bash scripts/build.sh)" >&2; exit 1; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

table() {  # table TITLE METRICS.csv
  echo "== $1"
  "$BIN/fit_bias" --in "$2" --out "$tmp/w.yaml" --cv point --coverage "$K" |
    sed -n '/^group/,/^coverage/{/^coverage/!p}; /^coverage/,$p'
  echo
}

table "article, leave one test point out (config/data/paper_d455_outdoor.csv)" \
  config/data/paper_d455_outdoor.csv

"$BIN/simulate" --protocol config/protocol_paper.yaml --metrics-only --seed 1 --out "$tmp/sim.csv"
table "simulated, article's protocol, calibrated sensor (metrics-only, 30 frames)" "$tmp/sim.csv"

cat > "$tmp/effects.yaml" <<'YAML'
effects:
  - {name: disparity_offset, delta_px: -0.2}
  - {name: temporal_drift, rate_px_per_s: 0.02}
YAML
"$BIN/simulate" --protocol config/protocol_paper.yaml --metrics-only --seed 2 \
  --effects "$tmp/effects.yaml" --out "$tmp/sim_offset.csv"
table "simulated, disparity offset -0.2 px and drift 0.02 px/s" "$tmp/sim_offset.csv"

# Many simulated tables: 32 rows per distance cannot tell a 2.3 % promise from 0 % or 6 %, so the
# simulator's side is pooled over SEEDS independent tables of the article's protocol (each fitted
# and held out on its own), calibrated sensor and with the offset and drift above.
SEEDS=${SEEDS:-10}
pooled() {  # pooled TITLE [--effects FILE]
  echo "== $1, $SEEDS seeds pooled"
  shift
  for s in $(seq 1 "$SEEDS"); do
    "$BIN/simulate" --protocol config/protocol_paper.yaml --metrics-only --seed $((100 + s)) \
      "$@" --out "$tmp/pool.csv" >/dev/null
    "$BIN/fit_bias" --in "$tmp/pool.csv" --out "$tmp/w.yaml" --cv point --coverage "$K" \
      2>/dev/null |
      awk '/^coverage/ { on = 1; next } on && $1 ~ /^[0-9.]+$/ { print $1, $2, $3, $8 }'
  done | awk -v k="$K" '
    { n[$1] += $2; b[$1] += $3; z2[$1] += $2 * $4 * $4 }
    END {
      printf "%10s %6s %7s %7s %6s\n", "distance_m", "n", "beyond", "share", "rms_z"
      for (d in n) printf "%10s %6d %7d %6.2f%% %6.2f\n", d, n[d], b[d], 100 * b[d] / n[d],
                          sqrt(z2[d] / n[d]) | "sort -n"
    }'
  echo
}
pooled "simulated, calibrated sensor"
pooled "simulated, disparity offset -0.2 px and drift 0.02 px/s" --effects "$tmp/effects.yaml"
