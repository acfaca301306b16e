#!/usr/bin/env bash
# The main job on the embedded default data (the article's 128 measurements, config/data/):
# installs what is missing, builds, then
#   1. fits the article's eq. 6 (paper6, λ = 0.001): reproduces its Table 6;
#   2. fits the default physics-grounded model, cross-validated, and writes its weights;
#   3. corrects every measurement with it (corrected distance, predicted bias, margin);
#   4. simulates the article's 128 recordings with the calibrated D455 model (metrics only);
#   5. end to end on recordings: simulates 8 of them as RealSense bags (config/protocol_demo.yaml),
#      lists one with bag_info, and measures them all with panel_extract (RANSAC, no boxes);
#   6. diagnoses the gap between the article's table and the simulator (diagnose_gap, about 25 s).
# Outputs go to OUT_DIR (default out/).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
export BUILD_DIR=${BUILD_DIR:-build}
bash scripts/build.sh >/dev/null
BIN="$BUILD_DIR/apps"
OUT=${OUT_DIR:-out}
mkdir -p "$OUT"
DATA=config/data/paper_d455_outdoor.csv

echo "== eq. 6 of the article (paper6, lambda 0.001): compare with config/data/paper_table6.csv"
"$BIN/fit_bias" --in "$DATA" --out "$OUT/weights_paper6.yaml" --model paper6 --lambda 0.001
echo
echo "== default model, cross-validated"
"$BIN/fit_bias" --in "$DATA" --out "$OUT/weights.yaml"
echo
echo "== corrected distances and safety margins"
"$BIN/correct_depth" --weights "$OUT/weights.yaml" --in "$DATA" --out "$OUT/corrected.csv"
echo
echo "== simulated article protocol, calibrated sensor (metrics only)"
"$BIN/simulate" --protocol config/protocol_paper.yaml --metrics-only --out "$OUT/sim_metrics.csv"
echo
echo "== simulated recordings → bags → panel_extract"
rm -rf "$OUT/sim_bags"
"$BIN/simulate" --protocol config/protocol_demo.yaml --out-dir "$OUT/sim_bags"
"$BIN/bag_info" "$OUT/sim_bags/sim_daylight_emitter-on_8m_20deg_HD.bag"
"$BIN/panel_extract" --manifest "$OUT/sim_bags/manifest.csv" --out "$OUT/sim_extract.csv" \
  --panels-out "$OUT/sim_panels.json" "$OUT/sim_bags"
echo
echo "== the sim-to-real gap of the article's table (diagnose_gap)"
"$BIN/diagnose_gap" --real "$DATA" --out "$OUT/gap"
echo
echo "outputs in $OUT/: weights_paper6.yaml weights.yaml corrected.csv sim_metrics.csv"
echo "  sim_bags/ (bags + manifest.csv) sim_extract.csv sim_panels.json gap/ (gap.json, report.md)"
