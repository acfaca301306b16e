#!/usr/bin/env bash
# The article reproduced end to end from the embedded data (config/data/), into OUT_DIR
# (default out/paper): installs what is missing, builds, then
#   1. fits eq. 6 (paper6, λ = 0.001) per light × preset and sets it beside the article's
#      Table 6 (tables/table6.csv, tables/table6.md);
#   2. fits the default model, cross-validated; the cross-validation table of both
#      (tables/cv_table.csv, .md; held-out errors per row in cv*.csv);
#   3. corrects every measurement with both (corrected*.csv: corrected distance, σ, safe distance)
#      and counts their over-reads and safe-distance coverage (tables/safety_table.csv, .md);
#   4. draws the figures (figures/): Figures 4, 5 and 6 of the article, the safety margin, and
#      real − sim heat maps against the metrics-only simulation of the protocol;
#   5. simulates the article's 128 recordings as RealSense bags and measures them with
#      panel_extract (sim_extract.csv), FRAMES frames each (default 10, the article's recordings
#      have 144–293: 10 keep the bags at 2.3 GB and find the panel in all 128; 5 miss it in 15
#      High Density recordings at 16 m); the bags are removed afterwards unless KEEP_BAGS=1;
#   6. the gap report on the article's data (gap/gap.json, gap/report.md) and its figures, when
#      build/apps/diagnose_gap exists (otherwise says it is skipped).
# Prints, and writes into OUT_DIR/summary.md, the tables and the run time of each step.
# DOCS_DIR=docs also copies the figures the README shows into docs/.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/paper}
FRAMES=${FRAMES:-10}
T_START=$(date +%s.%N)
since() { awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }

bash scripts/setup.sh
export BUILD_DIR=${BUILD_DIR:-build}
bash scripts/build.sh >/dev/null
BIN="$BUILD_DIR/apps"
PY=.venv/bin/python
DATA=config/data/paper_d455_outdoor.csv
TABLE6=config/data/paper_table6.csv
mkdir -p "$OUT/figures" "$OUT/tables"
SUMMARY="$OUT/summary.md.tmp"
: > "$SUMMARY"
TIMES=()
FAILED=()
T_BUILD=$(since "$T_START")
TIMES+=("set-up and build: $T_BUILD s")

echo "== 1-3. fits (eq. 6 at λ = 0.001, default model), cross-validation, corrections"
t=$(date +%s.%N)
"$BIN/fit_bias" --in "$DATA" --out "$OUT/weights_paper6.yaml" --model paper6 --lambda 0.001 \
  --cv-out "$OUT/cv_paper6.csv" | tee "$OUT/fit_paper6.txt"
"$BIN/fit_bias" --in "$DATA" --out "$OUT/weights.yaml" --cv-out "$OUT/cv.csv" |
  tee "$OUT/fit_default.txt"
"$BIN/correct_depth" --weights "$OUT/weights.yaml" --in "$DATA" --out "$OUT/corrected.csv"
"$BIN/correct_depth" --weights "$OUT/weights_paper6.yaml" --in "$DATA" \
  --out "$OUT/corrected_paper6.csv"
$PY scripts/plot_tables.py --paper6 "$OUT/weights_paper6.yaml" --article "$TABLE6" \
  --weights "$OUT/weights.yaml" \
  --safety disp_knots "$OUT/corrected.csv" "$OUT/cv.csv" \
  --safety "eq. 6" "$OUT/corrected_paper6.csv" "$OUT/cv_paper6.csv" --out-dir "$OUT/tables"
TIMES+=("fits, cross-validation, corrections, tables: $(since "$t") s")

echo
echo "== 4. figures"
t=$(date +%s.%N)
"$BIN/simulate" --protocol config/protocol_paper.yaml --metrics-only --out "$OUT/sim_metrics.csv"
$PY scripts/plot_error_vs_distance.py --in "$DATA" --out "$OUT/figures/fig4_error_vs_distance.png"
$PY scripts/plot_iso_error.py --weights "$OUT/weights_paper6.yaml" --weights "$OUT/weights.yaml" \
  --data "$DATA" --bin "$BIN" --out "$OUT/figures/fig5_iso_error.png"
$PY scripts/plot_corrected.py \
  --corrected "$OUT/corrected.csv" --label disp_knots --cv "$OUT/cv.csv" \
  --corrected "$OUT/corrected_paper6.csv" --label "eq. 6" --cv "$OUT/cv_paper6.csv" \
  --out "$OUT/figures/fig6_corrected.png"
$PY scripts/plot_margin.py --weights "$OUT/weights.yaml" --data "$DATA" --bin "$BIN" \
  --out "$OUT/figures/margin.png"
$PY scripts/plot_gap.py --real "$DATA" --sim "$OUT/sim_metrics.csv" \
  --out-dir "$OUT/figures/real_minus_sim"
TIMES+=("figures (and the metrics-only simulation): $(since "$t") s")

echo
echo "== 5. the article's 128 recordings simulated as bags ($FRAMES frames each) → panel_extract"
rm -rf "$OUT/sim_bags"
t=$(date +%s.%N)
"$BIN/simulate" --protocol config/protocol_paper.yaml --out-dir "$OUT/sim_bags" --frames "$FRAMES"
T_SIM=$(since "$t")
BAG_SIZE=$(du -sh "$OUT/sim_bags" | cut -f1)
t=$(date +%s.%N)
extract_status=0
"$BIN/panel_extract" --manifest "$OUT/sim_bags/manifest.csv" --out "$OUT/sim_extract.csv" \
  --panels-out "$OUT/sim_panels.json" --jobs 2 --quiet "$OUT/sim_bags" || extract_status=$?
T_EXTRACT=$(since "$t")
if [ ! -s "$OUT/sim_extract.csv" ]; then
  FAILED+=("panel_extract wrote no table (exit $extract_status)")
  FOUND="none"
else
  FOUND=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "status") s = i; next }
    s && $s == "ok" { n++ } END { print n + 0 }' "$OUT/sim_extract.csv")
  $PY scripts/plot_error_vs_distance.py --in "$OUT/sim_extract.csv" \
    --out "$OUT/figures/fig4_sim_extract.png" \
    --title "Simulated protocol through panel_extract: median depth - nominal distance"
fi
if [ "${KEEP_BAGS:-0}" != "1" ]; then rm -rf "$OUT/sim_bags"; fi
TIMES+=("simulate 128 recordings × $FRAMES frames: $T_SIM s ($BAG_SIZE of bags)")
TIMES+=("panel_extract on them (2 jobs): $T_EXTRACT s, panel found in $FOUND of 128")

echo
echo "== 6. gap report"
t=$(date +%s.%N)
if [ -x "$BIN/diagnose_gap" ]; then
  if "$BIN/diagnose_gap" --real "$DATA" --out "$OUT/gap"; then
    $PY scripts/plot_gap.py --gap "$OUT/gap/gap.json" --out-dir "$OUT/figures/gap" ||
      FAILED+=("plot_gap.py on $OUT/gap/gap.json")
    GAP_NOTE="gap/gap.json, gap/report.md; figures/gap/"
  else
    FAILED+=("diagnose_gap --real $DATA")
    GAP_NOTE="diagnose_gap failed"
  fi
else
  GAP_NOTE="skipped: $BIN/diagnose_gap is not built (the real - sim heat maps against the
metrics-only simulation are in figures/real_minus_sim/)"
  echo "gap report $GAP_NOTE"
fi
TIMES+=("gap report: $(since "$t") s")
if [ -n "${DOCS_DIR:-}" ]; then
  mkdir -p "$DOCS_DIR"
  for f in fig4_error_vs_distance fig5_iso_error fig6_corrected margin fig4_sim_extract; do
    if [ -f "$OUT/figures/$f.png" ]; then cp "$OUT/figures/$f.png" "$DOCS_DIR/$f.png"; fi
  done
  if [ -f "$OUT/figures/gap/gap_effects.png" ]; then
    mkdir -p "$DOCS_DIR/gap"
    for f in gap_heatmaps gap_effects gap_before_after; do
      cp "$OUT/figures/gap/$f.png" "$DOCS_DIR/gap/$f.png"
    done
    cp "$OUT/gap/gap.json" "$OUT/gap/report.md" "$DOCS_DIR/gap/"
  fi
  echo "README figures copied into $DOCS_DIR/"
fi
TOTAL=$(since "$T_START")

{
  echo "# The article reproduced"
  echo
  echo "Made by \`scripts/reproduce_paper.sh $OUT\` from \`$DATA\` on $(date -u +%Y-%m-%d)."
  echo
  echo "## Table 6 beside the article's"
  echo
  cat "$OUT/tables/table6.md"
  echo
  echo "## Cross-validation"
  echo
  cat "$OUT/tables/cv_table.md"
  echo
  echo "## Over-reads and safe distances"
  echo
  cat "$OUT/tables/safety_table.md"
  echo
  echo "## Outputs"
  echo
  echo "- weights_paper6.yaml, weights.yaml, fit_*.txt, cv*.csv (held-out error per row)"
  echo "- corrected.csv, corrected_paper6.csv"
  figures=$(cd "$OUT/figures" && find . -name '*.png' | sort | sed 's|^\./||' | tr '\n' ' ')
  echo "- figures/: $figures"
  echo "- sim_metrics.csv (metrics-only simulation), sim_extract.csv, sim_panels.json"
  echo "- gap: $GAP_NOTE"
  echo
  echo "## Run time"
  echo
  for line in "${TIMES[@]}"; do echo "- $line"; done
  echo "- total: $TOTAL s"
  if [ ${#FAILED[@]} -gt 0 ]; then
    echo
    echo "## Failed steps"
    echo
    for line in "${FAILED[@]}"; do echo "- $line"; done
  fi
} >> "$SUMMARY"
mv "$SUMMARY" "$OUT/summary.md"

echo
echo "== run time"
for line in "${TIMES[@]}"; do echo "  $line"; done
echo "reproduce_paper.sh: $TOTAL s in all; outputs and summary.md in $OUT/"
if [ ${#FAILED[@]} -gt 0 ]; then
  echo "reproduce_paper.sh: failed steps: ${FAILED[*]}" >&2
  exit 1
fi
