#!/usr/bin/env bash
# Coverage of the safe distance out of sample: per nominal distance, the share of held-out truths
# below corrected − k·σ (the dangerous side), leaving one test point out (both emitter rows of a
# point leave together; each is predicted by a fit, residual model included, that never saw it)
# and leaving one off-axis angle out (SCHEMES=point,angle by default: a margin must hold for an
# angle the fit has not seen).
# With a normal error, k = 2 promises at most 2.3 % beyond (the target: ≤ 2.5 %). p_promise says
# how likely the misses seen are under that promise, rms_z whether σ has the right size.
#   1. the article's 128 rows (config/data/paper_d455_outdoor.csv);
#   2. the simulator on the article's protocol (calibrated sensor, metrics-only path), without
#      and with a disparity offset of −0.2 px and a warm-up drift.
# Usage: bash scripts/coverage_table.sh [k]     (BUILD_DIR=build, SCHEMES=point,angle, SEEDS=10)
# ARTICLE=FILE replaces the article's table (config/data/paper_d455_outdoor.csv); SEEDS=0 skips
# the simulated tables.
set -euo pipefail
cd "$(dirname "$0")/.."
K=${1:-2}
BIN=${BUILD_DIR:-build}/apps
for app in fit_bias simulate; do
  [ -x "$BIN/$app" ] || { echo "coverage_table: $BIN/$app not built (bash scripts/build.sh)" >&2; exit 1; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# fit_bias's warnings (a cross-validation that could not run, a margin fitted to in-sample
# residuals) are part of the result: they go to stderr as fit_bias wrote them, only its routine
# summary line is dropped.
fit() {  # fit METRICS.csv: fit_bias with coverage tables on stdout, its warnings on stderr
  local rc=0
  "$BIN/fit_bias" --in "$1" --out "$tmp/w.yaml" --cv "$SCHEMES" --coverage "$K" \
    2>"$tmp/fit.err" || rc=$?
  grep -v '^fit_bias: [0-9]* groups from ' "$tmp/fit.err" >&2 || true
  # 1: rows that failed upstream were left out (the warning says so); the table stands.
  [ "$rc" -le 1 ] || { echo "coverage_table: fit_bias failed on $1 (exit $rc)" >&2; exit 1; }
}

SCHEMES=${SCHEMES:-point,angle}
table() {  # table TITLE METRICS.csv
  echo "== $1"
  fit "$2" | sed -n '/^group/,/^coverage/{/^coverage/!p}; /^coverage/,$p'
  echo
}

ARTICLE=${ARTICLE:-config/data/paper_d455_outdoor.csv}
table "article ($ARTICLE)" "$ARTICLE"
[ "${SEEDS:-10}" -gt 0 ] || exit 0

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
    fit "$tmp/pool.csv" |
      awk '/^coverage/ { on = 1; s = $0; sub(/.*held out \(/, "", s); sub(/\).*/, "", s); next }
           on && $1 ~ /^[0-9.]+$/ { print s, $1, $2, $3, $8 }'
  done | awk -v k="$K" '
    { key = $1 " " $2; n[key] += $3; b[key] += $4; z2[key] += $3 * $5 * $5 }
    END {
      printf "%8s %10s %6s %7s %7s %6s\n", "scheme", "distance_m", "n", "beyond", "share",
             "rms_z"
      for (d in n) printf "%8s %10s %6d %7d %6.2f%% %6.2f\n", substr(d, 1, index(d, " ") - 1),
                          substr(d, index(d, " ") + 1), n[d], b[d], 100 * b[d] / n[d],
                          sqrt(z2[d] / n[d]) | "sort -k1,1 -k2n"
    }'
  echo
}
pooled "simulated, calibrated sensor"
pooled "simulated, disparity offset -0.2 px and drift 0.02 px/s" --effects "$tmp/effects.yaml"
