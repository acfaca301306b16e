#!/usr/bin/env bash
# A user's own campaign in ROS 2 form, end to end, on simulated recordings (README: "Your own
# campaign with ROS 2"):
#   1. 16 test points (4, 8, 12, 16 m × 0, 10, 20, 35°; High Accuracy, emitter on, daylight),
#      simulated as rosbag2 MCAP recordings (simulate --format rosbag2, zstd chunks, the ROS 2
#      wrapper's topics and parameters), each put in its own rosbag2 folder with the
#      metadata.yaml `ros2 bag record` writes beside it: what a user's disk holds;
#   2. the manifest as a user writes it from the template (bag = folder name, distance_m,
#      angle_deg, light, preset, emitter);
#   3. bag_info on one folder; panel_extract → fit_bias → diagnose_gap → obstacle_detector with
#      the unit's weights, as the README says;
#   4. checks: 16 rows all ok with the manifest's preset, weights.yaml with the daylight/HA
#      group, gap.json, one detection line per frame.
#   bash scripts/test_ros2_campaign.sh [BUILD_DIR]      (ctest runs it: label "workflow")
# Every failing step says which, on one line, and the script exits non-zero.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
NAME=test_ros2_campaign
# shellcheck source=scripts/workflow_test_lib.sh
. "$ROOT/scripts/workflow_test_lib.sh"
use_build "${1:-}" simulate bag_info panel_extract fit_bias diagnose_gap obstacle_detector
WORK=$BUILD/ros2-campaign-test
rm -rf "$WORK"
mkdir -p "$WORK/sim" "$WORK/campaign"
FRAMES=3

# 1. Sixteen test points as rosbag2 MCAP recordings.
write_protocol "$WORK/protocol.yaml" "4, 8, 12, 16" "0, 10, 20, 35" HA $FRAMES
"$APPS/simulate" --protocol "$WORK/protocol.yaml" --out-dir "$WORK/sim" --format rosbag2 \
    --seed 3 --threads 2 >"$WORK/simulate.log" 2>&1 ||
  fail "simulate --format rosbag2 failed, see $WORK/simulate.log"
n=0
for mcap in "$WORK/sim"/*.mcap; do
  n=$((n + 1))
  name=$(printf 'tp%02d' "$n")
  mkdir "$WORK/campaign/$name"
  mv "$mcap" "$WORK/campaign/$name/${name}_0.mcap"
  cat >"$WORK/campaign/$name/metadata.yaml" <<EOF2
rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  relative_file_paths:
    - ${name}_0.mcap
  duration:
    nanoseconds: 100000000
  starting_time:
    nanoseconds_since_epoch: 1000000000
  message_count: $((2 * FRAMES + 1))
  topics_with_message_count: []
  compression_format: ""
  compression_mode: ""
EOF2
  # 2. The manifest row: what the tape and the notebook say (the simulator's truth here).
  base=$(basename "$mcap")
  grep "^$base," "$WORK/sim/manifest.csv" | cut -d, -f2-6 | sed "s/^/$name,/" \
      >>"$WORK/campaign/rows.csv"
done
[ "$n" -eq 16 ] || fail "simulate wrote $n recordings, expected 16"
{ echo "bag,distance_m,angle_deg,light,preset,emitter"; cat "$WORK/campaign/rows.csv"; } \
    >"$WORK/campaign/manifest.csv"
rm "$WORK/campaign/rows.csv"

# 3. The walk-through.
C=$WORK/campaign
"$APPS/bag_info" "$C/tp01" >"$WORK/bag_info.txt" 2>&1 || fail "bag_info $C/tp01 failed"
grep -q "Storage id:        mcap" "$WORK/bag_info.txt" || fail "bag_info: no storage id"
grep -q "(from parameter messages)" "$WORK/bag_info.txt" ||
  fail "bag_info: preset and emitter not read from the recorded parameters"
"$APPS/panel_extract" --quiet --manifest "$C/manifest.csv" --out "$WORK/metrics.csv" \
    --panels-out "$WORK/panels.json" --jobs 2 "$C" >"$WORK/panel_extract.log" 2>&1 ||
  fail "panel_extract failed, see $WORK/panel_extract.log"
rows=$(tail -n +2 "$WORK/metrics.csv" | wc -l)
ok=$(tail -n +2 "$WORK/metrics.csv" | grep -c ',ok,' || true)
[ "$rows" -eq 16 ] || fail "metrics.csv has $rows rows, expected 16"
[ "$ok" -eq 16 ] || fail "$ok of 16 rows ok in $WORK/metrics.csv"
grep -q '"settings_from": "manifest"' "$WORK/panels.json" ||
  fail "panels.json does not say the manifest gave preset and emitter"
"$APPS/fit_bias" --in "$WORK/metrics.csv" --out "$WORK/weights.yaml" >"$WORK/fit_bias.log" 2>&1 ||
  fail "fit_bias failed, see $WORK/fit_bias.log"
grep -q "light: daylight" "$WORK/weights.yaml" || fail "weights.yaml holds no daylight group"
grep -q "preset: HA" "$WORK/weights.yaml" || fail "weights.yaml holds no HA group"
"$APPS/diagnose_gap" --real "$WORK/metrics.csv" --out "$WORK/gap" --protocol "$WORK/protocol.yaml" \
    --frames 2 --threads 2 >"$WORK/diagnose_gap.log" 2>&1 ||
  fail "diagnose_gap failed, see $WORK/diagnose_gap.log"
[ -s "$WORK/gap/gap.json" ] || fail "no $WORK/gap/gap.json"
"$APPS/obstacle_detector" --weights "$WORK/weights.yaml" --light daylight \
    --out "$WORK/detections.jsonl" "$C/tp05" >"$WORK/obstacle_detector.log" 2>&1 ||
  fail "obstacle_detector failed, see $WORK/obstacle_detector.log"
lines=$(wc -l <"$WORK/detections.jsonl")
[ "$lines" -eq "$FRAMES" ] || fail "detections.jsonl has $lines lines for $FRAMES frames"
echo "test_ros2_campaign: 16 rosbag2 recordings -> 16 rows ok -> weights -> gap report ->" \
     "$lines frames of detections ($WORK)"
