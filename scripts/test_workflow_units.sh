#!/usr/bin/env bash
# The workflow (workflow/Snakefile) never drops a unit or a recording silently:
#   1. a folder of units beside one good unit: manifest.CSV (case), manifest.csv a folder, no
#      manifest, a manifest and no recording, a recording named .BAG, a folder named x.bag, a
#      recording outside any unit folder, an unreadable manifest (root skips that one):
#      snakemake refuses before any job, naming every one of them and what is wrong, and writes
#      nothing;
#   2. a unit with a truncated recording beside a good unit and a unit recorded as ROS 2 MCAP
#      files (-j 2, keep going): the corrupt recording's job fails with panel_extract's reason,
#      that unit stops, the two others finish, and the summary at the end names the unit, the
#      recording and its log.
#   bash scripts/test_workflow_units.sh [BUILD_DIR]     (ctest: workflow_units)
# Every failing check says which, on one line, and the script exits non-zero.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=test_workflow_units
# shellcheck source=scripts/workflow_test_lib.sh
. "$ROOT/scripts/workflow_test_lib.sh"
use_build "${1:-}" simulate panel_extract fit_bias
use_snakemake
WORK=$BUILD/workflow-units-test
rm -rf "$WORK"
mkdir -p "$WORK/run"
snake() {  # snake LOG UNITS_DIR: snakemake -j 2 (keep going), outputs in $WORK/results
  (cd "$WORK/run" && "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" -j 2 --keep-going \
      --config units_dir="$2" out_dir="$WORK/results" tools="$APPS" diagnose_gap=false) \
      >"$WORK/$1" 2>&1
}

write_protocol "$WORK/protocol.yaml" "4, 8, 12" "0, 20" HD 2
"$APPS/simulate" --protocol "$WORK/protocol.yaml" --out-dir "$WORK/sim" --seed 5 --threads 2 \
    >"$WORK/simulate.log" 2>&1 || fail "simulate failed, see $WORK/simulate.log"
good_unit() {  # good_unit DIR: the six simulated recordings and their manifest
  mkdir -p "$1"
  cp "$WORK/sim"/*.bag "$WORK/sim/manifest.csv" "$1/"
}
"$APPS/simulate" --protocol "$WORK/protocol.yaml" --out-dir "$WORK/sim_ros2" --format rosbag2 \
    --seed 5 --threads 2 >"$WORK/simulate_ros2.log" 2>&1 ||
  fail "simulate --format rosbag2 failed, see $WORK/simulate_ros2.log"
one_bag=$(cd "$WORK/sim" && ls ./*.bag | head -1)
one_bag=${one_bag#./}

# --- 1. Unit folders the workflow cannot process: all reported, nothing run ----------------
U=$WORK/units
good_unit "$U/good"
good_unit "$U/upper_case" && mv "$U/upper_case/manifest.csv" "$U/upper_case/manifest.CSV"
good_unit "$U/manifest_folder" && rm "$U/manifest_folder/manifest.csv" &&
  mkdir "$U/manifest_folder/manifest.csv"
good_unit "$U/no_manifest" && rm "$U/no_manifest/manifest.csv"
mkdir "$U/no_recording" && cp "$WORK/sim/manifest.csv" "$U/no_recording/"
good_unit "$U/bag_case" && mv "$U/bag_case/$one_bag" "$U/bag_case/${one_bag%.bag}.BAG"
good_unit "$U/bag_folder" && mkdir "$U/bag_folder/x.bag"
cp "$WORK/sim/$one_bag" "$U/stray.bag"
expected=(
  "unit upper_case ($U/upper_case): no manifest.csv, but manifest.CSV (names are case-sensitive)"
  "unit manifest_folder ($U/manifest_folder): manifest.csv is not a file"
  "unit no_manifest ($U/no_manifest): no manifest.csv"
  "unit no_recording ($U/no_recording): no recording (.bag, .mcap, .db3, folder with metadata.yaml)"
  "unit bag_case: ${one_bag%.bag}.BAG: a recording must end in '.bag' (names are case-sensitive)"
  "unit bag_folder: x.bag: named like a recording but not a file"
  "$U/stray.bag: a recording outside any unit folder"
)
if [ "$(id -u)" -ne 0 ]; then  # root reads any file: an unreadable manifest only for others
  good_unit "$U/unreadable" && chmod 000 "$U/unreadable/manifest.csv"
  expected+=("unit unreadable ($U/unreadable): manifest.csv is not readable")
fi
if snake refused.log "$U"; then
  fail "run 1: units that cannot be processed were skipped silently (exit 0), see $WORK/refused.log"
fi
grep -qF "workflow: ${#expected[@]} problem(s) in $U, nothing run:" "$WORK/refused.log" ||
  fail "run 1: not '${#expected[@]} problem(s) ... nothing run' in $WORK/refused.log"
for line in "${expected[@]}"; do
  grep -qF "  $line" "$WORK/refused.log" || fail "run 1: not reported: '$line'"
done
[ ! -e "$WORK/results" ] || fail "run 1: outputs written although the run was refused"

# --- 2. A corrupt recording: its unit stops, the other finishes, the summary names it -------
U2=$WORK/units2
good_unit "$U2/good"
good_unit "$U2/corrupt"
cp -r "$WORK/sim_ros2" "$U2/ros2"
size=$(stat -c %s "$U2/corrupt/$one_bag")
truncate -s $((size / 3)) "$U2/corrupt/$one_bag"
if snake corrupt.log "$U2"; then
  fail "run 2: a corrupt recording gave a successful run, see $WORK/corrupt.log"
fi
[ -s "$WORK/results/good/weights.yaml" ] || fail "run 2: the good unit did not finish"
[ -s "$WORK/results/ros2/weights.yaml" ] ||
  fail "run 2: the unit of MCAP recordings did not finish"
[ "$(grep -c ',ok,' "$WORK/results/ros2/metrics.csv")" -eq 6 ] ||
  fail "run 2: the unit of MCAP recordings has not 6 ok rows, see $WORK/results/ros2/metrics.csv"
[ ! -e "$WORK/results/corrupt/metrics.csv" ] ||
  fail "run 2: the corrupt unit got a metrics table"
[ ! -e "$WORK/results/corrupt/shards/${one_bag%.bag}.csv" ] ||
  fail "run 2: a shard left for the corrupt recording"
grep -qF "panel_extract failed on unit corrupt, $U2/corrupt/$one_bag (status error)" \
    "$WORK/corrupt.log" || fail "run 2: the job's error does not name the recording"
grep -q '^workflow: 3 unit(s): 2 done, 1 not done$' "$WORK/corrupt.log" ||
  fail "run 2: no summary '3 unit(s): 2 done, 1 not done' in $WORK/corrupt.log"
line=$(grep "^workflow: unit corrupt not done: panel_extract on $one_bag: " "$WORK/corrupt.log") ||
  fail "run 2: the summary does not name the corrupt unit's recording"
log=$WORK/results/corrupt/logs/panel_extract/${one_bag%.bag}.log
grep -qF "(log $log)" <<<"$line" && [ -s "$log" ] ||
  fail "run 2: the summary does not give the recording's log, or it is empty: $line"

echo "test_workflow_units: ${#expected[@]} unusable unit folders and recordings reported by" \
  "name, nothing run; a corrupt recording stops its unit alone, named in the summary with its" \
  "log; a unit of MCAP recordings processed"
