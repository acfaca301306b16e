#!/usr/bin/env bash
# The main job on the embedded default data (the article's 128 measurements, config/data/):
# installs what is missing, builds, then
#   1. fits the article's eq. 6 (paper6, λ = 0.001): reproduces its Table 6;
#   2. fits the default physics-grounded model, cross-validated, and writes its weights;
#   3. corrects every measurement with it (corrected distance, predicted bias, margin).
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
