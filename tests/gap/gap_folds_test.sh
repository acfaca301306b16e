#!/usr/bin/env bash
# scripts/gap_folds.py on a fresh diagnosis of the article's rows (two candidates, 4 frames a
# cell): every outer fold printed with its selection, and each simulated one with its Σz² metric
# by metric, which the script checks add up to the fold's total; then the same gap.json with one
# metric's Σz² moved by one, refused with one line naming the file and the fold (exit 2).
# Usage: gap_folds_test.sh DIAGNOSE_GAP PYTHON SOURCE_DIR
set -euo pipefail
APP=$1 PY=$2 SRC=$3
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
fail() { echo "gap_folds_test: $*" >&2; exit 1; }
"$APP" --real "$SRC/config/data/paper_d455_outdoor.csv" --candidates disparity_offset,depth_scale \
  --frames 4 --out "$D/out" > /dev/null
"$PY" "$SRC/scripts/gap_folds.py" "$D/out/gap.json" > "$D/folds.txt"
cat "$D/folds.txt"
[ "$(grep -c '^distance [0-9]* m (32 cells held out): ' "$D/folds.txt")" = 4 ] ||
  fail "not the four distances held out, 32 cells each"
simulated=$("$PY" -c 'import json, sys
print(sum(1 for f in json.load(open(sys.argv[1]))["how_far"]["nested"]["folds"] if f["simulated"]))' \
  "$D/out/gap.json")
[ "$simulated" -ge 1 ] || fail "no fold simulated"
[ "$(grep -c '^  simulated Σz², calibrated -> selection: ' "$D/folds.txt")" = "$simulated" ] ||
  fail "not one Σz² line per simulated fold"
[ "$(grep -c '^    median_bias_m: ' "$D/folds.txt")" = "$simulated" ] ||
  fail "the median's Σz² not printed for each simulated fold"
"$PY" - "$D/out/gap.json" "$D/bad.json" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
f = next(f for f in g["how_far"]["nested"]["folds"] if f["simulated"])
m = next(iter(f["simulated_sq_per_metric"]["selected"]))
f["simulated_sq_per_metric"]["selected"][m] += 1
json.dump(g, open(sys.argv[2], "w"))
PY
rc=0
"$PY" "$SRC/scripts/gap_folds.py" "$D/bad.json" > /dev/null 2> "$D/err" || rc=$?
[ "$rc" = 2 ] || fail "a gap.json whose metrics do not add up: exit $rc, not 2"
[ "$(wc -l < "$D/err")" = 1 ] || fail "more than one line: $(cat "$D/err")"
grep -q "^gap_folds: .*bad.json: fold [0-9] (distance [0-9]* m): the metrics' Σz² add up to " \
  "$D/err" || fail "the error does not name the file and the fold: $(cat "$D/err")"
echo "gap_folds_test: ok"
