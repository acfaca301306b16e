#!/usr/bin/env bash
# scripts/gap_folds.py on a fresh diagnosis of the article's rows (two candidates, 4 frames a
# cell): every outer fold printed with its selection, and each simulated one with its Σz² metric
# by metric, which the script checks against the fold's total and its held-out cells' own z;
# then the same gap.json broken three ways, each refused.
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
[ "$(grep -Ec '^distance [0-9]+ m \(32 cells held out\): ' "$D/folds.txt")" = 4 ] ||
  fail "not the four distances held out, 32 cells each"
simulated=$("$PY" -c 'import json, sys
print(sum(1 for f in json.load(open(sys.argv[1]))["how_far"]["nested"]["folds"] if f["simulated"]))' \
  "$D/out/gap.json")
[ "$simulated" -ge 1 ] || fail "no fold simulated"
[ "$(grep -c '^  simulated Σz², calibrated -> selection: ' "$D/folds.txt")" = "$simulated" ] ||
  fail "not one Σz² line per simulated fold"
[ "$(grep -c '^    median_bias_m: ' "$D/folds.txt")" = "$simulated" ] ||
  fail "the median's Σz² not printed for each simulated fold"
# Three ways to break it, each refused with one line naming the file and the fold (exit 2): one
# metric's Σz² moved by one (the fold's total no longer adds up), two metrics' Σz² swapped (the
# total holds, the held-out cells' own z do not), an effect of the selection left out of params.
"$PY" - "$D/out/gap.json" "$D" <<'PY'
import json, sys
src, out = sys.argv[1], sys.argv[2]
def broken(name, change):
    g = json.load(open(src))
    f = next(f for f in g["how_far"]["nested"]["folds"] if f["simulated"] and f["selected"])
    change(f)
    json.dump(g, open(f"{out}/{name}.json", "w"))
def moved(f):
    sel = f["simulated_sq_per_metric"]["selected"]
    sel[next(iter(sel))] += 1
def swapped(f):
    sel = f["simulated_sq_per_metric"]["selected"]
    a, b = sorted(sel, key=sel.get)[:2][0], sorted(sel, key=sel.get)[-1]
    sel[a], sel[b] = sel[b], sel[a]
def dropped(f):
    del f["params"][f["selected"][0]]
broken("moved", moved)
broken("swapped", swapped)
broken("dropped", dropped)
PY
for case in moved:"the metrics' Σz² add up to" swapped:"Σz² with the selection is .*, its held-out cells' own z give" \
            dropped:"params name"; do
  name=${case%%:*} what=${case#*:}
  rc=0
  "$PY" "$SRC/scripts/gap_folds.py" "$D/$name.json" > "$D/$name.out" 2> "$D/$name.err" || rc=$?
  [ "$rc" = 2 ] || fail "$name: exit $rc, not 2"
  [ ! -s "$D/$name.out" ] || fail "$name: printed before refusing"
  [ "$(wc -l < "$D/$name.err")" = 1 ] || fail "$name: more than one line: $(cat "$D/$name.err")"
  grep -Eq "^gap_folds: .*$name.json: fold [0-9] \(distance [0-9]+ m\): .*$what" "$D/$name.err" ||
    fail "$name: the error does not name the file, the fold and the fault: $(cat "$D/$name.err")"
done
echo "gap_folds_test: ok"
