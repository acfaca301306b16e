#!/usr/bin/env bash
# Benchmark of simulate (lib/sim), printed beside its targets:
#  1. rendering and writing 1280x720 depth frames into RealSense bags (target >= 200 frames/s):
#     16 recordings x FRAMES frames (one light, preset and emitter of the article's protocol),
#     the whole run timed: scene set-up, rendering, bag writing, manifest with the truth;
#  2. the metrics-only path on the article's 128-cell protocol, 30 frames a cell (target < 1 s),
#     with the default threads (all cores) and with one thread; the whole process timed.
# Usage: scripts/bench_simulate.sh [BUILD_DIR]   (OUT_DIR=/tmp/... FRAMES=30 REPEAT=3)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-${BUILD_DIR:-build}}
SIM="$BUILD_DIR/apps/simulate"
[ -x "$SIM" ] || { echo "bench_simulate: $SIM not built (run scripts/build.sh)" >&2; exit 1; }
FRAMES=${FRAMES:-30}
REPEAT=${REPEAT:-3}
OUT_DIR=${OUT_DIR:-$(mktemp -d /tmp/bench_simulate.XXXXXX)}
trap 'rm -rf "$OUT_DIR"' EXIT
mkdir -p "$OUT_DIR"

cat > "$OUT_DIR/protocol.yaml" <<YAML
protocol: {lights: [daylight], presets: [HA], emitters: ["off"], frames: $FRAMES}
YAML

now() { date +%s.%N; }
best() { sort -g | head -1; }

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
     "load $(cut -d' ' -f1-3 /proc/loadavg)"

times=()
for _ in $(seq "$REPEAT"); do
  rm -rf "$OUT_DIR/bags"
  t0=$(now)
  "$SIM" --protocol "$OUT_DIR/protocol.yaml" --sensor config/sensor_calibrated.yaml \
         --out-dir "$OUT_DIR/bags" > /dev/null
  t1=$(now)
  times+=("$(echo "$t1 - $t0" | bc -l)")
done
write_s=$(printf '%s\n' "${times[@]}" | best)
frames=$((16 * FRAMES))
bytes=$(du -cb "$OUT_DIR"/bags/*.bag | tail -1 | cut -f1)
printf '%-44s %10s %12s %14s\n' "case" "seconds" "measured" "target"
printf '%-44s %10.3f %8.0f f/s %14s\n' "render + write bags ($frames frames, 1280x720)" \
  "$write_s" "$(echo "$frames / $write_s" | bc -l)" ">= 200 f/s"
printf '%-44s %10s %8.0f MB/s\n' "  bag bytes written" "" "$(echo "$bytes / 1e6 / $write_s" | bc -l)"
rm -rf "$OUT_DIR/bags"

for threads in default 1; do
  args=()
  [ "$threads" = default ] || args=(--threads "$threads")
  times=()
  for _ in $(seq "$REPEAT"); do
    t0=$(now)
    "$SIM" --protocol config/protocol_paper.yaml --metrics-only --frames 30 \
           --out "$OUT_DIR/metrics.csv" "${args[@]}"
    t1=$(now)
    times+=("$(echo "$t1 - $t0" | bc -l)")
  done
  s=$(printf '%s\n' "${times[@]}" | best)
  printf '%-44s %10.3f %12s %14s\n' "metrics-only, 128 cells x 30 frames, threads $threads" \
    "$s" "" "< 1 s"
done
echo "(best of $REPEAT runs each; rows: $(($(wc -l < "$OUT_DIR/metrics.csv") - 1)))"
