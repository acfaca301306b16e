#!/usr/bin/env bash
# The withheld cases of the gap diagnosis as a table, judged by the strict criteria
# (lib/gap/cases.h, docs/gap/cases.md): every test point placed off by 2 % of its distance, then
# every registered effect at two sizes, a sunset-only disparity offset, offset + drift,
# offset + scale, an offset at the noise floor, effects outside the registry, a user's unit
# of 32 rows (simulated), a user's unit recorded as field bags (scripts/make_field_campaign.py,
# through panel_extract), effects injected by their physics into real tables (the article's
# 128 rows; a user's field campaign of 32, tests/data/field_unit_seed11.csv): a disparity
# offset and a depth scale at 1.5 and 0.5 times the limits each table's own report gives,
# judged on what the injection moved, and two effects outside the registry injected into the
# same tables (a far over-read ∝ D² in the median alone, one test point read far, each at 1.5
# times what the table's own report could miss); and 20 tables without effect. A case passes
# only when the selected set equals the injected set (outside the registry: nothing selected,
# `unexplained` names the right cells), sizes are within 20 %, and the simulated held-out shrink
# is >= 70 % (of the injected part, on the article); the null suite when at least 19 of 20
# select nothing. Columns: case, injected, selected, recovered, largest
# size error, simulated shrink, unexplained, pass, every criterion not met.
# CI (tests/gap/withheld_test.cpp) asserts the criteria and the cases that pass.
# One seed is one draw of every case's noise and placement; --seeds N runs seeds 1 to N (each
# into OUT_DIR/seed-S) and prints how often each case passes (scripts/gap_cases_seeds.py), also
# written to OUT_DIR/seeds.md, then what the range-law cases' tables allow: the smallest
# standard error of each size under the placement scatter and, seed by seed, whether the
# table's own medians put the sizes within 20 % (scripts/gap_bounds.py, OUT_DIR/bounds.md).
# --first-seed S starts them at S (S to S + N - 1): seeds no change was chosen on, for a figure
# no choice has seen (a case's table is drawn at S + 999 + its index, so from S = 101 on no table
# of seeds 1 to 25 comes again).
# About 5 minutes a seed on 2 cores.
# Usage: scripts/gap_cases.sh [BUILD_DIR] [OUT_DIR] [--no-field] [--seeds N] [--first-seed S]
#   OUT_DIR/cases.md is written too; the field bags go to OUT_DIR/field (or a temporary folder).
set -euo pipefail
trap 'echo "gap_cases: failed at line $LINENO" >&2' ERR
cd "$(dirname "$0")/.."
FIELD=1
SEEDS=0
FIRST=1
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --no-field) FIELD=0 ;;
    --seeds)
      [ $# -ge 2 ] && [[ "$2" =~ ^[1-9][0-9]*$ ]] ||
        { echo "gap_cases: --seeds needs a count >= 1" >&2; exit 2; }
      SEEDS=$2
      shift ;;
    --first-seed)
      [ $# -ge 2 ] && [[ "$2" =~ ^[1-9][0-9]*$ ]] ||
        { echo "gap_cases: --first-seed needs a seed >= 1" >&2; exit 2; }
      FIRST=$2
      shift ;;
    *) ARGS+=("$1") ;;
  esac
  shift
done
[ "$FIRST" = 1 ] || [ "$SEEDS" != 0 ] || { echo "gap_cases: --first-seed needs --seeds" >&2; exit 2; }
BUILD_DIR=${ARGS[0]:-${BUILD_DIR:-build}}
OUT_DIR=${ARGS[1]:-}
APP="$BUILD_DIR/apps/diagnose_gap"
EXTRACT="$BUILD_DIR/apps/panel_extract"
[ -x "$APP" ] || { echo "gap_cases: $APP not built (run scripts/build.sh)" >&2; exit 1; }
OPTS=(--inject-into config/data/paper_d455_outdoor.csv --inject-into tests/data/field_unit_seed11.csv)
[ -n "$OUT_DIR" ] && OPTS+=(--out "$OUT_DIR")
if [ "$FIELD" = 1 ]; then
  [ -x "$EXTRACT" ] || { echo "gap_cases: $EXTRACT not built" >&2; exit 1; }
  if [ -n "$OUT_DIR" ]; then
    FIELD_DIR="$OUT_DIR/field"
  else
    FIELD_DIR=$(mktemp -d)
    trap 'rm -rf "$FIELD_DIR"' EXIT
  fi
  mkdir -p "$FIELD_DIR"
  .venv/bin/python scripts/make_field_campaign.py "$FIELD_DIR" --jobs 2 > "$FIELD_DIR/bags.log"
  # Exit 1 (some rows failed) still writes the table: the diagnosis lists those rows.
  "$EXTRACT" --manifest "$FIELD_DIR/manifest.csv" --out "$FIELD_DIR/field.csv" --quiet \
    "$FIELD_DIR" || [ $? -eq 1 ]
  OPTS+=(--field "$FIELD_DIR/field.csv")
fi
if [ "$SEEDS" = 0 ]; then
  "$APP" --cases "${OPTS[@]}"
  exit 0
fi
[ -n "$OUT_DIR" ] || { echo "gap_cases: --seeds needs OUT_DIR" >&2; exit 2; }
TABLES=()
LAST=$((FIRST + SEEDS - 1))
for ((s = FIRST; s <= LAST; s++)); do
  SEED_OPTS=("${OPTS[@]}")
  # The --out pair is the seed's own folder.
  for i in "${!SEED_OPTS[@]}"; do
    if [ "${SEED_OPTS[$i]}" = "--out" ]; then SEED_OPTS[$((i + 1))]="$OUT_DIR/seed-$s"; fi
  done
  echo "gap_cases: seed $s ($FIRST to $LAST)" >&2
  "$APP" --cases --seed "$s" "${SEED_OPTS[@]}" > /dev/null
  TABLES+=("$OUT_DIR/seed-$s/cases.md")
done
.venv/bin/python scripts/gap_cases_seeds.py "${TABLES[@]}" > "$OUT_DIR/seeds.md.tmp"
mv "$OUT_DIR/seeds.md.tmp" "$OUT_DIR/seeds.md"
cat "$OUT_DIR/seeds.md"
# What the range-law cases' tables allow, seed by seed (scripts/gap_bounds.py).
SEED_DIRS=()
for ((s = FIRST; s <= LAST; s++)); do SEED_DIRS+=("$OUT_DIR/seed-$s"); done
.venv/bin/python scripts/gap_bounds.py --tables "${SEED_DIRS[@]}" > "$OUT_DIR/bounds.md.tmp"
mv "$OUT_DIR/bounds.md.tmp" "$OUT_DIR/bounds.md"
echo
cat "$OUT_DIR/bounds.md"
