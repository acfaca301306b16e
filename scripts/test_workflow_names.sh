#!/usr/bin/env bash
# The workflow (workflow/Snakefile) on hostile names: recordings and unit folders named by
# whoever copied the files. Four runs on small simulated units:
#   A. two units whose folder and recording names hold $(...), backticks, ';', '|', '>', '&',
#      spaces, quotes and a leading '-': every recording processed under its own name
#      (one shard each, the unit's metrics.csv identical to one panel_extract run over the
#      folder), nothing executed (no PWNED file anywhere), no stray file, the inputs unchanged;
#   B. names Snakemake cannot carry to its jobs (a newline in a recording's and in a unit's
#      name; braces, a single quote, a backslash, a comma, a leading double quote in a
#      recording's):
#      refused before anything runs, each named (escaped) in the error, nothing executed,
#      nothing written;
#   C. a tool that fails (panel_extract on a broken --config) on a hostile name: the job fails
#      with the tool's own error and its log named, no shard left behind, no "latency" story;
#   D. a --config value with a single quote: refused, naming the setting.
#   bash scripts/test_workflow_names.sh [BUILD_DIR]     (ctest: workflow_hostile_names)
# Every failing check says which, on one line, and the script exits non-zero.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=test_workflow_names
# shellcheck source=scripts/workflow_test_lib.sh
. "$ROOT/scripts/workflow_test_lib.sh"
use_build "${1:-}" simulate panel_extract fit_bias diagnose_gap
use_snakemake
WORK=$BUILD/workflow-names-test
rm -rf "$WORK"
mkdir -p "$WORK/sim" "$WORK/tools" "$WORK/run"
for tool in "$APPS"/*; do
  [ -x "$tool" ] && [ -f "$tool" ] && ln -s "$tool" "$WORK/tools/"
done
# Where a shell that ran a name would leave its mark: snakemake's folder, the tools', the
# inputs', the outputs', the repository, the home and /tmp.
no_pwned() {  # no_pwned RUN
  local found
  # find's status is not the answer: a folder another test removes while find walks /tmp makes
  # it exit 1, which pipefail would turn into a silent end of this script.
  found=$({ find "$WORK" "$ROOT" "$HOME" /tmp -maxdepth 4 -name 'PWNED*' 2>/dev/null || true; } |
    head -3)
  [ -z "$found" ] || fail "run $1: a name was executed by a shell: $found"
}
rm -f "$HOME"/PWNED* /tmp/PWNED* 2>/dev/null || true
no_pwned "before"

# 8 recordings: 4 distances × 2 angles, High Density, emitter on, daylight; 3 frames each.
write_protocol "$WORK/protocol.yaml" "4, 6, 8, 10" "0, 20" HD 3
"$APPS/simulate" --protocol "$WORK/protocol.yaml" --out-dir "$WORK/sim" --seed 3 --threads 2 \
    >"$WORK/simulate.log" 2>&1 || fail "simulate failed, see $WORK/simulate.log"

# make_units DEST UNIT=NAME,NAME,... ...: copies the simulated bags under the hostile names
# (in order) into DEST/UNIT/, with a manifest.csv whose bag column names them.
make_units() {
  "$PYTHON" - "$WORK/sim" "$@" <<'EOF'
import csv, os, shutil, sys
sim, dest, specs = sys.argv[1], sys.argv[2], sys.argv[3:]
with open(os.path.join(sim, "manifest.csv"), newline="") as f:
    rows = list(csv.DictReader(f))
for spec in specs:
    unit, names = spec.split("=", 1)[0], spec.split("=", 1)[1].split("\x1f")
    folder = os.path.join(dest, unit)
    os.makedirs(folder)
    out_rows = []
    for name, row in zip(names, rows):
        shutil.copyfile(os.path.join(sim, row["bag"]), os.path.join(folder, name + ".bag"))
        out_rows.append(dict(row, bag=name + ".bag"))
    with open(os.path.join(folder, "manifest.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()), lineterminator="\n")
        w.writeheader()
        w.writerows(out_rows)
EOF
}
US=$'\x1f'  # separates names in make_units' specs
snake() {  # snake RUN UNITS_DIR OUT_DIR [MORE CONFIG...]: snakemake in $WORK/run, log RUN.log
  local run=$1 units=$2 out=$3
  shift 3
  (cd "$WORK/run" && "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" -j 2 \
      --config units_dir="$units" out_dir="$out" tools="$WORK/tools" diagnose_gap=true "$@") \
      >"$WORK/$run.log" 2>&1
}

# --- A. hostile names, all processed --------------------------------------------------------
UNIT1='unit $(touch PWNED_unit1) `touch PWNED_unit1b`'
UNIT2='-unit;touch PWNED_unit2 & echo "x" > PWNED_unit2b'
NAMES1=('$(touch PWNED_dollar)' '`touch PWNED_backtick`' 'a;touch PWNED_semicolon;b'
        'rec a' 'a "quoted" name' '-leading' 'x > PWNED_redirect | touch PWNED_pipe &'
        '~root && touch PWNED_and')
NAMES2=('-rf' '--out' '$HOME' 'a b  c' '*' 'a=b:c' 'x "$(touch PWNED_dq)" x' 'ok')
make_units "$WORK/units" "$UNIT1=$(IFS=$US; echo "${NAMES1[*]}")" \
    "$UNIT2=$(IFS=$US; echo "${NAMES2[*]}")" || fail "could not make the units"
before=$(cd "$WORK/units" && find . -type f -print0 | sort -z | xargs -0 sha256sum)
snake A "$WORK/units" "$WORK/results" || fail "run A: snakemake failed, see $WORK/A.log"
no_pwned A
after=$(cd "$WORK/units" && find . -type f -print0 | sort -z | xargs -0 sha256sum)
[ "$before" = "$after" ] || fail "run A: the input folder changed"
# Every file written is one the workflow promises, under the recording's own name.
"$PYTHON" - "$WORK/results" "$UNIT1" "$UNIT2" "${#NAMES1[@]}" "${NAMES1[@]}" "${NAMES2[@]}" \
    <<'EOF' || fail "run A: outputs are not the promised set (above)"
import os, sys
out, unit1, unit2, n1 = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
names = {unit1: sys.argv[5:5 + n1], unit2: sys.argv[5 + n1:]}
want = set()
for unit, recs in names.items():
    for r in recs:
        want.add(os.path.join(unit, "shards", r + ".csv"))
        want.add(os.path.join(unit, "logs", "panel_extract", r + ".log"))
    for f in ("metrics.csv", "weights.yaml", "fit_bias.log", "diagnose_gap.log", "gap/gap.json",
              "gap/report.md"):
        want.add(os.path.join(unit, f))
have = set()
for d, _, files in os.walk(out):
    have.update(os.path.relpath(os.path.join(d, f), out) for f in files)
missing, stray = sorted(want - have), sorted(have - want)
stray = [s for s in stray if not s.split(os.sep)[1:2] == ["gap"]]  # gap/ may hold more
for m in missing:
    print(f"  missing: {m!r}", file=sys.stderr)
for s in stray:
    print(f"  stray: {s!r}", file=sys.stderr)
sys.exit(1 if missing or stray else 0)
EOF
stray=$(find "$WORK/run" -mindepth 1 -maxdepth 1 ! -name .snakemake | head -3)
[ -z "$stray" ] || fail "run A: stray files where snakemake ran: $stray"
for unit in "$UNIT1" "$UNIT2"; do
  "$APPS/panel_extract" --manifest "$WORK/units/$unit/manifest.csv" --quiet \
      --out "$WORK/one_run.csv" "$WORK/units/$unit" >"$WORK/one_run.log" 2>&1 ||
    fail "panel_extract over $WORK/units/$unit failed, see $WORK/one_run.log"
  cmp -s "$WORK/results/$unit/metrics.csv" "$WORK/one_run.csv" ||
    fail "run A: $unit: metrics.csv differs from one panel_extract run over the unit"
  ok_rows=$(grep -c ',ok,' "$WORK/results/$unit/metrics.csv" || true)
  [ "$ok_rows" -eq 8 ] || fail "run A: $unit: $ok_rows of 8 rows ok (manifest rows not matched?)"
  grep -q '^groups:' "$WORK/results/$unit/weights.yaml" || fail "run A: $unit: no fitted group"
done

# --- B. names Snakemake cannot carry: refused before anything runs, by name -----------------
REFUSED=($'rec\n$(touch PWNED_newline)' '{recording}$(touch PWNED_b)' "it's \$(touch PWNED_q)"
         'back\slash' '"quoted"' 'a,b')
make_units "$WORK/units_nl" "unit_ok=$(IFS=$US; echo "${REFUSED[*]}")" $'unit\nb=ok' ||
  fail "could not make the units of run B"
if snake B "$WORK/units_nl" "$WORK/results_nl"; then
  fail "run B: names Snakemake cannot carry were accepted, see $WORK/B.log"
fi
no_pwned B
grep -qF "'rec\\n\$(touch PWNED_newline).bag'" "$WORK/B.log" ||
  fail "run B: the recording with a newline is not named in $WORK/B.log"
grep -qF "'$WORK/units_nl/unit\\nb'" "$WORK/B.log" ||
  fail "run B: the unit with a newline is not named in $WORK/B.log"
for refused in '{recording}$(touch PWNED_b).bag: a brace' \
    "it's \$(touch PWNED_q).bag: a single quote" 'back\slash.bag: a single quote or backslash' \
    '"quoted".bag: a double quote at the start' 'a,b.bag: a comma'; do
  grep -qF "$refused" "$WORK/B.log" || fail "run B: no '$refused...' in $WORK/B.log"
done
[ ! -e "$WORK/results_nl" ] || fail "run B: outputs written although the run was refused"

# --- C. a tool that fails on a hostile name: its own error, no partial output ---------------
printf 'ransac: [unclosed\n' >"$WORK/broken config.yaml"
make_units "$WORK/units_fail" "unit \$(touch PWNED_c)=rec; touch PWNED_c2" ||
  fail "could not make the failing unit"
if snake C "$WORK/units_fail" "$WORK/results_fail" panel_config="$WORK/broken config.yaml"; then
  fail "run C: a failing panel_extract gave a successful run, see $WORK/C.log"
fi
no_pwned C
grep -qF 'panel_extract failed on unit unit $(touch PWNED_c)' "$WORK/C.log" ||
  fail "run C: the tool's failure is not reported as the tool's, see $WORK/C.log"
grep -qF 'broken config.yaml' "$WORK/C.log" ||
  fail "run C: the tool's own error (the config it refused) is not in $WORK/C.log"
! grep -qi 'latency' "$WORK/C.log" || fail "run C: blamed on file-system latency, see $WORK/C.log"
shards=$(find "$WORK/results_fail" -path '*/shards/*' 2>/dev/null | wc -l)
[ "$shards" -eq 0 ] || fail "run C: $shards partial shard(s) left behind"

# --- D. a setting Snakemake cannot pass to its jobs: refused, named --------------------------
if snake D "$WORK/units" "$WORK/results_d" "fit_args=--lambda '1'"; then
  fail "run D: a setting with a single quote was accepted, see $WORK/D.log"
fi
grep -qF 'workflow: setting fit_args: a control character, single quote or backslash' \
    "$WORK/D.log" || fail "run D: the setting is not named in $WORK/D.log"
[ ! -e "$WORK/results_d" ] || fail "run D: outputs written although the run was refused"

echo "test_workflow_names: 16 hostile recording names in 2 hostile units processed under their" \
  "own names, nothing executed, no stray file; 7 names Snakemake cannot carry refused by name;" \
  "a failing tool reported as itself with no partial output"
