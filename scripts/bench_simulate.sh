#!/usr/bin/env bash
# Benchmark of simulate (lib/sim), printed beside its targets:
#  1. rendering and writing 1280x720 depth frames into RealSense bags (target >= 200 frames/s):
#     16 recordings x FRAMES frames (one light, preset and emitter of the article's protocol),
#     the whole run timed: scene set-up, rendering, bag writing, manifest with the truth;
#     (frames/s on wall time, and the bound 2 cores would give from the CPU time used, which
#     says what an idle machine does when the machine is shared);
#  2. the metrics-only path on the article's 128-cell protocol, 30 frames a cell (target < 1 s),
#     with the default threads (all cores) and with one thread; the whole process timed.
# Usage: scripts/bench_simulate.sh [BUILD_DIR]   (OUT_DIR=/tmp/... FRAMES=30 REPEAT=3)
set -euo pipefail
# A command failing inside an assigned $(...) would end the script without a word under set -e:
# say which. Figures are assigned before they are printed (scripts/bench_lib.sh).
trap 'echo "bench_simulate: line $LINENO failed: $BASH_COMMAND" >&2' ERR
cd "$(dirname "$0")/.."
BENCH=bench_simulate
source scripts/bench_lib.sh
BUILD_DIR=${1:-${BUILD_DIR:-build}}
SIM="$BUILD_DIR/apps/simulate"
[ -x "$SIM" ] || { echo "bench_simulate: $SIM not built (run scripts/build.sh)" >&2; exit 1; }
FRAMES=${FRAMES:-30}
REPEAT=${REPEAT:-3}
bench_positive_int FRAMES "$FRAMES"
bench_positive_int REPEAT "$REPEAT"
OUT_DIR=${OUT_DIR:-$(mktemp -d /tmp/bench_simulate.XXXXXX)}
trap 'rm -rf "$OUT_DIR"' EXIT
mkdir -p "$OUT_DIR"

cat > "$OUT_DIR/protocol.yaml" <<YAML
protocol: {lights: [daylight], presets: [HA], emitters: ["off"], frames: $FRAMES}
YAML

# Runs a command under /usr/bin/time; prints "wall_s cpu_s" (cpu = user + system).
timed() {
  /usr/bin/time -f "%e %U %S" -o "$OUT_DIR/time.txt" "$@" > /dev/null ||
    { echo "bench_simulate: $* failed" >&2; return 1; }
  awk '{printf "%s %.3f\n", $1, $2 + $3}' "$OUT_DIR/time.txt"
}

machine=$(bench_machine)
echo "machine: $machine"

runs=()
for ((i = 0; i < REPEAT; i++)); do
  rm -rf "$OUT_DIR/bags"
  runs+=("$(timed "$SIM" --protocol "$OUT_DIR/protocol.yaml" \
            --sensor config/sensor_calibrated.yaml --out-dir "$OUT_DIR/bags")")
done
best_run=$(printf '%s\n' "${runs[@]}" | best)  # assigned first: a failure here is reported
read -r write_s write_cpu <<< "$best_run"
frames=$((16 * FRAMES))
bytes=$(du -cb "$OUT_DIR"/bags/*.bag | tail -1 | cut -f1)
write_fps=$(bench_ratio "$frames" "$write_s")
bytes_per_s=$(bench_ratio "$bytes" "$write_s")
write_mbps=$(bench_ratio "$bytes_per_s" 1000000)
bound_fps=$(bench_ratio "$((2 * frames))" "$write_cpu")
printf '%-52s %8s %8s %14s %12s\n' "case" "wall_s" "cpu_s" "measured" "target"
printf '%-52s %8.3f %8.3f %10.0f f/s %12s\n' "render + write bags ($frames frames 1280x720)" \
  "$write_s" "$write_cpu" "$write_fps" ">= 200 f/s"
printf '%-52s %8s %8s %9.0f MB/s\n' "  bag bytes written" "" "" "$write_mbps"
printf '%-52s %8s %8s %10.0f f/s\n' "  frames per CPU-second / 2 cores (idle-machine bound)" "" "" \
  "$bound_fps"
rm -rf "$OUT_DIR/bags"

for threads in default 1; do
  args=()
  [ "$threads" = default ] || args=(--threads "$threads")
  runs=()
  for ((i = 0; i < REPEAT; i++)); do
    runs+=("$(timed "$SIM" --protocol config/protocol_paper.yaml --metrics-only --frames 30 \
              --out "$OUT_DIR/metrics.csv" "${args[@]}")")
  done
  best_run=$(printf '%s\n' "${runs[@]}" | best)
  read -r s cpu <<< "$best_run"
  printf '%-52s %8.3f %8.3f %14s %12s\n' "metrics-only, 128 cells x 30 frames, threads $threads" \
    "$s" "$cpu" "" "< 1 s"
done
lines=$(wc -l < "$OUT_DIR/metrics.csv")
echo "(best of $REPEAT runs each; rows: $((lines - 1)))"
