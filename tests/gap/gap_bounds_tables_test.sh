#!/usr/bin/env bash
# scripts/gap_bounds.py --tables on case folders made here, whose medians carry a known law:
# a disparity offset of 0.35 px read back as 0.35 (within 20 %) where the case passed, one of
# 0.5 px read beyond 20 % of 0.35 where it failed (0.46–0.54: the law's secant is taken at the
# injected 0.35 px); a sunset-only offset of 0.15 px read
# on the sunset test points alone, daylight carrying another offset that must not count; an
# offset of 0.15 px beside a drift whose median shift (0.09 px) is taken off, every size read
# from the injected column of the folder's cases.md; then a gap.json without cells and an
# injected column without a size, each refused by name.
# Usage: gap_bounds_tables_test.sh PYTHON SOURCE_DIR
set -euo pipefail
PY=$1 SRC=$2
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
fail() { echo "gap_bounds_tables_test: $*" >&2; exit 1; }
"$PY" - "$D" <<'PY'
import json, math, os, random, sys
out = sys.argv[1]
fb = 640 * 0.095  # config/sensor_calibrated.yaml
rng = random.Random(20261130)
def table(offset_of_light, spread):
    cells = []
    for light in ("daylight", "sunset"):
        for d in (4, 8, 12, 16):
            for a in (0, 10, 20, 35):
                z = d * math.cos(math.radians(a))
                placed = rng.gauss(0, spread * z)  # one draw a test point, shared
                for preset in ("HA", "HD"):
                    for emitter in ("off", "on"):
                        move = fb / (fb / z + offset_of_light[light]) - z
                        sim = rng.uniform(-0.05, 0.05)  # the base's own bias: taken off
                        cells.append({"light": light, "preset": preset, "emitter": emitter,
                                      "distance_m": d, "angle_deg": a,
                                      "real": {"median_bias_m": sim + move + placed},
                                      "sim": {"median_bias_m": sim}})
    return {"settings": {"frames": 10}, "cells": cells}
row = "| {} | {} | - | - | - | - | - | {} | |\n"
for seed, size, passed in (("seed-a", 0.35, "yes"), ("seed-b", 0.5, "**no**")):
    os.makedirs(f"{out}/{seed}/cases")
    with open(f"{out}/{seed}/cases/disparity_offset_large.json", "w") as f:
        json.dump(table({"daylight": size, "sunset": size}, 0.001), f)
    with open(f"{out}/{seed}/cases/disparity_offset_sunset_only.json", "w") as f:
        json.dump(table({"daylight": 0.4, "sunset": 0.15}, 0.001), f)
    # Beside a drift of 0.6 px/s over 10 frames at 30 fps, the medians move as 0.15 + 0.09 px.
    with open(f"{out}/{seed}/cases/disparity_offset___temporal_drift.json", "w") as f:
        json.dump(table({"daylight": 0.24, "sunset": 0.24}, 0.001), f)
    with open(f"{out}/{seed}/cases.md", "w") as f:
        f.write("| case | injected | selected | recovered | max error | simulated shrink | "
                "unexplained | pass | why not |\n|---|---|---|---|---|---|---|---|---|\n")
        # The sizes read against are the injected column's (0.35 at both seeds).
        f.write(row.format("disparity_offset large", "disparity_offset (delta_px 0.35)", passed))
        f.write(row.format("disparity_offset sunset only",
                           "disparity_offset (delta_px 0.15, sunset only)", "**no**"))
        f.write(row.format("disparity_offset + temporal_drift",
                           "disparity_offset (delta_px 0.15); temporal_drift (rate_px_per_s 0.6)",
                           "**no**"))
os.makedirs(f"{out}/broken/cases")
with open(f"{out}/broken/cases/disparity_offset_large.json", "w") as f:
    json.dump({"selected": []}, f)
with open(f"{out}/broken/cases.md", "w") as f:
    f.write(row.format("disparity_offset large", "disparity_offset (delta_px 0.35)", "yes"))
# A row whose injected column names no size: refused by name, not read against a guess.
os.makedirs(f"{out}/unsized/cases")
with open(f"{out}/unsized/cases/disparity_offset_large.json", "w") as f:
    json.dump(table({"daylight": 0.35, "sunset": 0.35}, 0.001), f)
with open(f"{out}/unsized/cases.md", "w") as f:
    f.write(row.format("disparity_offset large", "disparity_offset (delta_px)", "yes"))
PY
"$PY" "$SRC/scripts/gap_bounds.py" --protocol "$SRC/config/protocol_paper.yaml" \
  --sensor "$SRC/config/sensor_calibrated.yaml" --tables "$D/seed-a" "$D/seed-b" > "$D/out.txt"
cat "$D/out.txt"
grep -Eq '^\| disparity_offset large \| 1 of 2 \| 1 of 2 \| seed-a: 0\.35[0-9]* \(holds; passed\); seed-b: 0\.(4[6-9]|5[0-4])[0-9]* \(misses; failed\) \|$' \
  "$D/out.txt" || fail "the offset's tables not read as 0.35 (held, passed) and 0.5 (missed, failed)"
[ "$(sed -n "/the table's medians put/,\$p" "$D/out.txt" | grep -c '^| depth_scale')" = 0 ] ||
  fail "a case without tables printed"
grep -Eq '^\| disparity_offset sunset only \| 2 of 2 \| 0 of 2 \| seed-a: 0\.1(4[5-9]|5[0-5])[0-9]* \(holds; failed\); seed-b: 0\.1(4[5-9]|5[0-5])[0-9]* \(holds; failed\) \|$' \
  "$D/out.txt" || fail "the sunset-only offset not read on the sunset test points alone"
grep -Eq '^\| disparity_offset \+ temporal_drift \| 2 of 2 \| 0 of 2 \| seed-a: 0\.1(4[5-9]|5[0-5])[0-9]* \(holds; failed\); ' \
  "$D/out.txt" || fail "the offset beside the drift not read with the drift's shift taken off"
rc=0
"$PY" "$SRC/scripts/gap_bounds.py" --protocol "$SRC/config/protocol_paper.yaml" \
  --sensor "$SRC/config/sensor_calibrated.yaml" --tables "$D/broken" > /dev/null 2> "$D/err" || rc=$?
[ "$rc" = 1 ] || fail "a gap.json without cells: exit $rc, not 1"
grep -q "^gap_bounds: $D/broken/cases/disparity_offset_large.json: cannot read its cells" "$D/err" ||
  fail "a gap.json without cells not refused by name: $(cat "$D/err")"
[ "$(grep -c Traceback "$D/err")" = 0 ] || fail "a traceback: $(cat "$D/err")"
rc=0
"$PY" "$SRC/scripts/gap_bounds.py" --protocol "$SRC/config/protocol_paper.yaml" \
  --sensor "$SRC/config/sensor_calibrated.yaml" --tables "$D/unsized" > /dev/null 2> "$D/err" || rc=$?
[ "$rc" = 1 ] || fail "an injected column without a size: exit $rc, not 1"
grep -q "^gap_bounds: $D/unsized/cases.md: \"disparity_offset large\": cannot read the range laws' sizes" \
  "$D/err" || fail "an injected column without a size not refused by name: $(cat "$D/err")"
[ "$(grep -c Traceback "$D/err")" = 0 ] || fail "a traceback: $(cat "$D/err")"
echo "gap_bounds_tables_test: ok"
