#!/usr/bin/env bash
# The Snakemake workflow (workflow/Snakefile) on one machine, on two small simulated units:
#   1. simulates two units with BUILD_DIR/apps/simulate (6 recordings of 3 frames each, 1280×720,
#      two seeds), each a folder of bags with its manifest.csv;
#   2. runs `snakemake -j 2` with the project's .venv on them (tools from BUILD_DIR/apps);
#   3. checks the outputs: one shard per recording, each unit's metrics.csv identical to one
#      panel_extract run over the unit's folder, weights.yaml with a group, a gap report per unit
#      (gap.json with its baseline_gap, report.md); and
#      that a second run has nothing to do; and, when snakemake-executor-plugin-slurm is installed,
#      that the cluster profile (workflow/profiles/slurm) plans the same jobs (dry run).
#   bash scripts/test_workflow.sh [BUILD_DIR]        (ctest runs it: label "workflow")
# Every failing step says which, on one line, and the script exits non-zero.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=test_workflow
# shellcheck source=scripts/workflow_test_lib.sh
. "$ROOT/scripts/workflow_test_lib.sh"
use_build "${1:-}" simulate panel_extract fit_bias
use_snakemake
WORK=$BUILD/workflow-test
rm -rf "$WORK"
mkdir -p "$WORK/units" "$WORK/tools"
start=$(date +%s.%N)

# 1. Two units: 3 distances × 2 angles, High Density, emitter on, daylight; 3 frames each.
write_protocol "$WORK/protocol.yaml" "4, 8, 12" "0, 20" HD 3
seed=1
for unit in unit_a unit_b; do
  "$APPS/simulate" --protocol "$WORK/protocol.yaml" --out-dir "$WORK/units/$unit" \
      --seed $seed --threads 2 >"$WORK/simulate_$unit.log" 2>&1 ||
    fail "simulate for $unit failed, see $WORK/simulate_$unit.log"
  seed=$((seed + 1))
done

# 2. The workflow, with the built tools.
for tool in "$APPS"/*; do
  [ -x "$tool" ] && [ -f "$tool" ] && ln -s "$tool" "$WORK/tools/"
done
[ -e "$WORK/tools/diagnose_gap" ] || fail "$APPS/diagnose_gap is not built"
(cd "$WORK" && "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" -j 2 \
    --config units_dir="$WORK/units" out_dir="$WORK/results" tools="$WORK/tools" \
    diagnose_gap=true) >"$WORK/snakemake.log" 2>&1 ||
  fail "snakemake failed, see $WORK/snakemake.log"
end=$(date +%s.%N)

# 3. Outputs.
for unit in unit_a unit_b; do
  out=$WORK/results/$unit
  bags=$(ls "$WORK/units/$unit"/*.bag | wc -l)
  shards=$(ls "$out/shards"/*.csv 2>/dev/null | wc -l)
  [ "$bags" -eq 6 ] || fail "$unit: $bags recordings simulated, expected 6"
  [ "$shards" -eq "$bags" ] || fail "$unit: $shards shards for $bags recordings"
  "$APPS/panel_extract" --manifest "$WORK/units/$unit/manifest.csv" --quiet \
      --out "$WORK/$unit.one_run.csv" "$WORK/units/$unit" >"$WORK/$unit.one_run.log" 2>&1 ||
    fail "panel_extract over $WORK/units/$unit failed, see $WORK/$unit.one_run.log"
  cmp -s "$out/metrics.csv" "$WORK/$unit.one_run.csv" ||
    fail "$unit: merged metrics.csv differs from one panel_extract run over the unit"
  ok_rows=$(grep -c ',ok,' "$out/metrics.csv" || true)
  [ "$ok_rows" -eq "$bags" ] || fail "$unit: $ok_rows of $bags rows ok in $out/metrics.csv"
  grep -q '^groups:' "$out/weights.yaml" && grep -q 'light: daylight' "$out/weights.yaml" ||
    fail "$unit: $out/weights.yaml holds no fitted group"
  grep -q '"baseline_gap"' "$out/gap/gap.json" 2>/dev/null ||
    fail "$unit: no gap report in gap/gap.json"
  [ -s "$out/gap/report.md" ] || fail "$unit: no gap/report.md"
done
(cd "$WORK" && "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" -n --quiet \
    --config units_dir="$WORK/units" out_dir="$WORK/results" tools="$WORK/tools" \
    diagnose_gap=true) >"$WORK/snakemake_again.log" 2>&1 ||
  fail "snakemake -n failed, see $WORK/snakemake_again.log"
grep -qi "nothing to be done" "$WORK/snakemake_again.log" ||
  fail "a second run would redo work, see $WORK/snakemake_again.log"

# The cluster profile, when its executor is installed (workflow/requirements-cluster.txt): the
# same workflow planned through it (a dry run submits nothing).
PROFILE="not checked (snakemake-executor-plugin-slurm not in .venv)"
if "$PYTHON" -c "import snakemake_executor_plugin_slurm" 2>/dev/null; then
  (cd "$WORK" && "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" -n \
      --profile "$ROOT/workflow/profiles/slurm" --config units_dir="$WORK/units" \
      out_dir="$WORK/results_cluster" tools="$WORK/tools" diagnose_gap=true) \
      >"$WORK/snakemake_slurm.log" 2>&1 ||
    fail "snakemake -n --profile workflow/profiles/slurm failed, see $WORK/snakemake_slurm.log"
  grep -Eq 'panel_extract +12' "$WORK/snakemake_slurm.log" ||
    fail "the slurm profile's plan lacks 12 panel_extract jobs, see $WORK/snakemake_slurm.log"
  PROFILE="planned (dry run)"
fi

jobs=$(grep -cE '^(local)?rule ' "$WORK/snakemake.log" || true)
echo "test_workflow: 2 units × 6 recordings: $jobs jobs, outputs checked, a second run has" \
  "nothing to do; slurm profile $PROFILE;" \
  "$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') s simulate + snakemake"
