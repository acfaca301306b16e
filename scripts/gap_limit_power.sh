#!/usr/bin/env bash
# How often diagnose_gap sees an effect injected by its physics into a real table at multiples
# of the limit the table's own report publishes: a disparity offset and a depth scale on the
# over-reading side (lib/gap/cases.h, RealInjectionCases), at each seed, then the table of
# scripts/gap_limit_power.py (also written to OUT_DIR/power.md). The tables default to the
# article's rows and the field unit of tests/data; about a minute a seed and table pair on 2 cores.
# A case whose limit lies beyond its grid on a table is left out (diagnose_gap says which).
# Usage: scripts/gap_limit_power.sh BUILD_DIR OUT_DIR [--seeds N] [--times LIST] [TABLE.csv ...]
#   (paths from the source tree's root)
set -euo pipefail
trap 'echo "gap_limit_power: failed at line $LINENO" >&2' ERR
cd "$(dirname "$0")/.."
SEEDS=5
TIMES=1,1.5,2,3
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds)
      [ $# -ge 2 ] && [[ "$2" =~ ^[1-9][0-9]*$ ]] ||
        { echo "gap_limit_power: --seeds needs a count >= 1" >&2; exit 2; }
      SEEDS=$2
      shift ;;
    --times)
      [ $# -ge 2 ] || { echo "gap_limit_power: --times needs a list" >&2; exit 2; }
      TIMES=$2
      shift ;;
    *) ARGS+=("$1") ;;
  esac
  shift
done
[ ${#ARGS[@]} -ge 2 ] || { echo "usage: $0 BUILD_DIR OUT_DIR [--seeds N] [--times LIST] [TABLE.csv ...]" >&2; exit 2; }
APP="${ARGS[0]}/apps/diagnose_gap"
OUT_DIR=${ARGS[1]}
TABLES=("${ARGS[@]:2}")
[ ${#TABLES[@]} -gt 0 ] ||
  TABLES=(config/data/paper_d455_outdoor.csv tests/data/field_unit_seed11.csv)
[ -x "$APP" ] || { echo "gap_limit_power: $APP not built (run scripts/build.sh)" >&2; exit 1; }
OPTS=()
CASES=()
IFS=, read -r -a MULTIPLES <<< "$TIMES"
for m in "${MULTIPLES[@]}"; do
  # diagnose_gap names a case by the multiple as %g prints it: plain decimals only.
  [[ "$m" =~ ^[0-9]*\.?[0-9]+$ ]] ||
    { echo "gap_limit_power: --times: '$m' is not a plain decimal" >&2; exit 2; }
done
for t in "${TABLES[@]}"; do
  [ -f "$t" ] || { echo "gap_limit_power: $t: no such table" >&2; exit 2; }
  OPTS+=(--inject-into "$t")
  stem=$(basename "$t")
  stem=${stem%.*}
  for e in disparity_offset depth_scale; do
    for m in "${MULTIPLES[@]}"; do CASES+=(--case "$stem + $e ($m × its limit)"); done
  done
done
FOLDERS=()
for ((s = 1; s <= SEEDS; s++)); do
  echo "gap_limit_power: seed $s of $SEEDS" >&2
  "$APP" --cases --seed "$s" "${OPTS[@]}" --inject-times "$TIMES" "${CASES[@]}" \
    --out "$OUT_DIR/seed-$s" > /dev/null
  FOLDERS+=("$OUT_DIR/seed-$s")
done
.venv/bin/python scripts/gap_limit_power.py "${FOLDERS[@]}" > "$OUT_DIR/power.md.tmp"
mv "$OUT_DIR/power.md.tmp" "$OUT_DIR/power.md"
cat "$OUT_DIR/power.md"
