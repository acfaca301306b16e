#!/usr/bin/env bash
# Benchmark of obstacle_detector (lib/detect) on 1280x720 recordings, one core, the whole
# process timed (start-up, weights, bag reading, detection, JSONL written), beside two peers on
# the same bag and the same core:
#   - librealsense's own playback alone (pyrealsense2 from .venv, non-real-time, every depth
#     frame's pixels touched): what any detector built on librealsense pays before computing;
#   - depthbias's BagReader alone (bag_info --read-all): this detector's share spent reading;
# and the detector with PCL's own classes in place of the hand-written stages, on the same bag:
# pcl::VoxelGrid (voxel.use_pcl), pcl::ConditionalEuclideanClustering with the range-dependent
# tolerance as its condition (cluster.use_pcl), and both; their detections compared with the
# default run's (identical, or how many obstacles differ and by how much).
# The recording: simulate's obstacle scene (config/protocol_obstacles.yaml: seven people, two
# bushes, a hedge; High Density, emitter on), FRAMES frames. Target: >= 30 frames/s.
# Usage: bash scripts/bench_obstacle_detector.sh   (BUILD_DIR=build FRAMES=150 REPEAT=3 CORE=0)
set -euo pipefail
# A command failing inside an assigned $(...) would end the script without a word under set -e:
# say which. Figures are assigned before they are printed (scripts/bench_lib.sh).
trap 'echo "bench_obstacle_detector: line $LINENO failed: $BASH_COMMAND" >&2' ERR
here=$(dirname "$0")  # assigned: a failure here reaches the ERR trap
cd "$here/.."
BENCH=bench_obstacle_detector
source scripts/bench_lib.sh
BIN=${BUILD_DIR:-build}/apps
FRAMES=${FRAMES:-150}
REPEAT=${REPEAT:-3}
CORE=${CORE:-0}
bench_positive_int FRAMES "$FRAMES"
bench_positive_int REPEAT "$REPEAT"
[[ "$CORE" =~ ^[0-9]+$ ]] || { echo "bench_obstacle_detector: CORE must be a core number, not '$CORE'" >&2; exit 1; }
PY=.venv/bin/python
for app in obstacle_detector simulate fit_bias bag_info; do
  [ -x "$BIN/$app" ] || { echo "bench_obstacle_detector: $BIN/$app not built" >&2; exit 1; }
done
[ -x "$PY" ] || { echo "bench_obstacle_detector: $PY missing (bash scripts/setup.sh)" >&2; exit 1; }
OUT=$(mktemp -d /tmp/bench_obstacle_detector.XXXXXX)
trap 'rm -rf "$OUT"' EXIT

sed -e 's/presets: \[HA, HD\]/presets: [HD]/' -e "s/frames: 30/frames: $FRAMES/" \
  config/protocol_obstacles.yaml > "$OUT/protocol.yaml"
sed -i "s|^sensor: .*|sensor: $PWD/config/sensor_calibrated.yaml|" "$OUT/protocol.yaml"
"$BIN/simulate" --protocol "$OUT/protocol.yaml" --out-dir "$OUT/bags" > /dev/null
BAG=$(ls "$OUT"/bags/*.bag)
"$BIN/fit_bias" --in config/data/paper_d455_outdoor.csv --out "$OUT/w.yaml" > /dev/null

cat > "$OUT/playback.py" <<'PY'
import sys, time
import numpy as np
import pyrealsense2 as rs
path, expected = sys.argv[1], int(sys.argv[2])
ctx = rs.context()
dev = ctx.load_device(path)
pb = dev.as_playback()
pb.set_real_time(False)
sensor = dev.first_depth_sensor()
prof = [p for p in sensor.get_stream_profiles() if p.stream_type() == rs.stream.depth][0]
done, total = [], [0]
def on_frame(f):
    total[0] += int(np.asanyarray(f.get_data())[360, 640])
    done.append(time.perf_counter())
sensor.open(prof)
sensor.start(on_frame)
deadline = time.time() + 600
while len(done) < expected and time.time() < deadline:
    time.sleep(0.001)
sensor.stop()
sensor.close()
print(len(done))
PY

# Wall seconds of a command pinned to one core (the whole process).
timed() {
  /usr/bin/time -f "%e" -o "$OUT/time.txt" taskset -c "$CORE" "$@" > "$OUT/stdout.txt" ||
    { echo "bench_obstacle_detector: $* failed" >&2; return 1; }
  cat "$OUT/time.txt"
}
# Best of REPEAT; the first failed run fails it (the loop's last status alone would hide it).
run() { { for ((i = 0; i < REPEAT; i++)); do timed "$@" || exit 1; done; } | best; }

det_s=$(run "$BIN/obstacle_detector" --weights "$OUT/w.yaml" \
          --config config/obstacle_detector.yaml --out "$OUT/d.jsonl" "$BAG")
lines=$(wc -l < "$OUT/d.jsonl")
obst=$({ grep -o '"points"' "$OUT/d.jsonl" || true; } | wc -l)
# The same detector with PCL's classes in place of the hand-written stages.
pcl_in() {  # pcl_in SECTION...: the committed config with use_pcl true in those sections
  local script=""
  for section in "$@"; do script+="/^$section:/,/^[a-z]/ s/use_pcl: false/use_pcl: true/;"; done
  sed "$script" config/obstacle_detector.yaml
}
pcl_in voxel > "$OUT/vox.yaml"
pcl_in cluster > "$OUT/clu.yaml"
pcl_in voxel cluster > "$OUT/both.yaml"
for v in vox clu both; do
  grep -q 'use_pcl: true' "$OUT/$v.yaml" ||
    { echo "bench_obstacle_detector: $v.yaml sets no use_pcl" >&2; exit 1; }
done
declare -A var_s
for v in vox clu both; do
  var_s[$v]=$(run "$BIN/obstacle_detector" --weights "$OUT/w.yaml" --config "$OUT/$v.yaml" \
                --out "$OUT/d_$v.jsonl" "$BAG")
done
# Detections of a variant against the default run's.
cat > "$OUT/compare.py" <<'PY'
import json, sys
a = [json.loads(l) for l in open(sys.argv[1])]
b = [json.loads(l) for l in open(sys.argv[2])]
if open(sys.argv[1]).read() == open(sys.argv[2]).read():
    print("identical"); sys.exit()
total = sum(len(f["obstacles"]) for f in a)
counts = sum(len(x["obstacles"]) != len(y["obstacles"]) for x, y in zip(a, b))
points = zones = 0
dr = 0.0
for x, y in zip(a, b):
    if len(x["obstacles"]) != len(y["obstacles"]):
        continue
    for p, q in zip(x["obstacles"], y["obstacles"]):
        points += p["points"] != q["points"]
        zones += p["zone"] != q["zone"]
        dr = max(dr, abs(p["safe_range_m"] - q["safe_range_m"]))
print(f"{counts} frames with another obstacle count; {points} of {total} obstacles with other "
      f"points, safe range within {dr * 1000:.1f} mm, {zones} zones changed")
PY
read_s=$(run "$BIN/bag_info" --read-all "$BAG")
play_s=$(run "$PY" "$OUT/playback.py" "$BAG" "$FRAMES")
played=$(cat "$OUT/stdout.txt")

machine=$(bench_machine)
bag_mb=$(du -m "$BAG" | cut -f1)
per_frame=$(bench_ratio "$obst" "$lines")
det_fps=$(bench_ratio "$lines" "$det_s")
play_fps=$(bench_ratio "$played" "$play_s")
read_fps=$(bench_ratio "$FRAMES" "$read_s")
declare -A var_fps var_cmp
for v in vox clu both; do
  var_fps[$v]=$(bench_ratio "$lines" "${var_s[$v]}")
  var_cmp[$v]=$("$PY" "$OUT/compare.py" "$OUT/d.jsonl" "$OUT/d_$v.jsonl")
done
echo "machine: $machine; one core (taskset -c $CORE), best of $REPEAT"
printf 'recording: %s frames 1280x720, %s MB; detector found %.1f obstacles per frame\n' \
  "$FRAMES" "$bag_mb" "$per_frame"
printf '%-58s %8s %12s %12s\n' "case (whole process)" "wall_s" "measured" "target"
printf '%-58s %8.2f %8.1f f/s %12s\n' "obstacle_detector (read, detect, correct, JSONL)" \
  "$det_s" "$det_fps" ">= 30 f/s"
declare -A label=([vox]="... with pcl::VoxelGrid" [clu]="... with pcl::ConditionalEuclideanClustering"
                  [both]="... with both")
for v in vox clu both; do
  printf '%-58s %8.2f %8.1f f/s   %s\n' "${label[$v]}" "${var_s[$v]}" "${var_fps[$v]}" \
    "${var_cmp[$v]}"
done
printf '%-58s %8.2f %8.1f f/s\n' "peer: librealsense playback alone (pyrealsense2)" \
  "$play_s" "$play_fps"
printf '%-58s %8.2f %8.1f f/s\n' "peer: depthbias BagReader alone (bag_info --read-all)" \
  "$read_s" "$read_fps"
