#!/usr/bin/env bash
# Benchmark of diagnose_gap on the article's 128-row table with every candidate effect and
# leave-one-distance-out cross-validation nested in an outer hold-out (the defaults), printed
# beside its targets (≤ 30 s on a 2-core machine, aim 10 s) and beside its peer inside the run: the simulator's metrics-only
# path on the same 128 cells (one simulation of the table), which the diagnosis calls about a
# hundred times. Then the same diagnosis with its simulations kept between runs (--cache DIR):
# once simulating and keeping them, then taking them back, its outputs checked against the run
# without, byte for byte. Wall time and CPU time (user + system) of the whole process, best of
# REPEAT; the machine's load is printed (a shared machine gives less than its cores).
# Usage: scripts/bench_diagnose_gap.sh [BUILD_DIR]   (REPEAT=3 OUT_DIR=/tmp/...)
set -euo pipefail
# A command failing inside an assigned $(...) would end the script without a word under set -e:
# say which. Figures are assigned before they are printed (scripts/bench_lib.sh).
trap 'echo "bench_diagnose_gap: line $LINENO failed: $BASH_COMMAND" >&2' ERR
here=$(dirname "$0")  # assigned: a failure here reaches the ERR trap
cd "$here/.."
BENCH=bench_diagnose_gap
source scripts/bench_lib.sh
BUILD_DIR=${1:-${BUILD_DIR:-build}}
APP="$BUILD_DIR/apps/diagnose_gap"
SIM="$BUILD_DIR/apps/simulate"
for b in "$APP" "$SIM"; do
  [ -x "$b" ] || { echo "bench_diagnose_gap: $b not built (run scripts/build.sh)" >&2; exit 1; }
done
REPEAT=${REPEAT:-3}
bench_positive_int REPEAT "$REPEAT"
# The kept simulations go to a folder of the script's own, removed at the end.
CACHE_DIR=$(mktemp -d /tmp/bench_diagnose_gap_cache.XXXXXX)
if [ -n "${OUT_DIR:-}" ]; then  # the user's folder: written into, never removed
  mkdir -p "$OUT_DIR"
  trap 'rm -rf "$CACHE_DIR"' EXIT
else
  OUT_DIR=$(mktemp -d /tmp/bench_diagnose_gap.XXXXXX)
  trap 'rm -rf "$OUT_DIR" "$CACHE_DIR"' EXIT
fi
REAL=config/data/paper_d455_outdoor.csv

timed() {  # prints "wall_s cpu_s"
  /usr/bin/time -f "%e %U %S" -o "$OUT_DIR/time.txt" "$@" > /dev/null ||
    { echo "bench_diagnose_gap: $* failed" >&2; return 1; }
  awk '{printf "%s %.2f\n", $1, $2 + $3}' "$OUT_DIR/time.txt"
}
machine=$(bench_machine)
echo "machine: $machine"
runs=() sims=() kept=()
for ((i = 0; i < REPEAT; i++)); do
  runs+=("$(timed "$APP" --real "$REAL" --out "$OUT_DIR/out")")
  sims+=("$(timed "$SIM" --protocol config/protocol_paper.yaml --metrics-only --frames 10 \
              --out "$OUT_DIR/m.csv")")
done
# The same diagnosis with its simulations kept (--cache): one run that simulates and keeps them,
# then REPEAT that take them back; their outputs must be the cold run's, byte for byte.
keeping=$(timed "$APP" --real "$REAL" --out "$OUT_DIR/keeping" --cache "$CACHE_DIR")
for ((i = 0; i < REPEAT; i++)); do
  kept+=("$(timed "$APP" --real "$REAL" --out "$OUT_DIR/kept" --cache "$CACHE_DIR")")
done
for f in gap.json report.md; do
  for run in keeping kept; do
    cmp -s "$OUT_DIR/out/$f" "$OUT_DIR/$run/$f" ||
      { echo "bench_diagnose_gap: $run/$f differs from the run without --cache" >&2; exit 1; }
  done
done
n_sims=$({ grep -o '"simulations": [0-9]*' "$OUT_DIR/out/gap.json" || true; } | grep -o '[0-9]*$' ||
  echo "?")
wall=$(printf '%s\n' "${runs[@]}" | cut -d' ' -f1 | best)
cpu=$(printf '%s\n' "${runs[@]}" | cut -d' ' -f2 | best)
swall=$(printf '%s\n' "${sims[@]}" | cut -d' ' -f1 | best)
scpu=$(printf '%s\n' "${sims[@]}" | cut -d' ' -f2 | best)
kwall=$(printf '%s\n' "${kept[@]}" | cut -d' ' -f1 | best)
kcpu=$(printf '%s\n' "${kept[@]}" | cut -d' ' -f2 | best)
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
echo "load after: $load_after"
printf '%-58s %9s %9s %s\n' "case (best of $REPEAT)" "wall [s]" "CPU [s]" "target"
n_cand=$(python3 -c 'import json, sys; print(len(json.load(open(sys.argv[1]))["settings"]["candidates"]))' \
  "$OUT_DIR/out/gap.json" 2>/dev/null || echo "?")
printf '%-58s %9s %9s %s\n' "diagnose_gap, 128 rows, $n_cand candidates, nested LODO ($n_sims sims)" \
  "$wall" "$cpu" "≤ 30 s wall on 2 cores (aim 10 s)"
printf '%-58s %9s %9s %s\n' "the same, simulating and keeping them (--cache, once)" \
  "${keeping% *}" "${keeping#* }" "the first run on these cells"
printf '%-58s %9s %9s %s\n' "the same, its simulations kept (--cache, taken back)" \
  "$kwall" "$kcpu" "outputs byte-identical to the run above"
printf '%-58s %9s %9s %s\n' "peer: simulate --metrics-only, 128 cells x 10 frames" \
  "$swall" "$scpu" "one of the $n_sims"
over_two=$(bench_ratio "$cpu" 2)
printf 'CPU time over 2 cores (an idle 2-core machine): %.1f s\n' "$over_two"
# Every run, not only the best: a shared machine's speed can move by a quarter within an hour.
every=$(printf '%s\n' "${runs[@]}" | cut -d' ' -f1 | paste -sd' ' -)
printf 'diagnose_gap, every run, wall [s]: %s\n' "$every"
