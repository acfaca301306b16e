# What the end-to-end tests of the workflow share; sourced, never run. Before sourcing, a test
# sets ROOT (the source tree) and NAME (its name in messages).
#   fail MESSAGE...               one line "NAME: MESSAGE" on stderr, exit 1
#   use_build BUILD_ARG TOOL...   BUILD (absolute) and APPS; every TOOL built, else fail
#   use_snakemake                 PYTHON (the build's DEPTHBIAS_PYTHON, else .venv) and SNAKEMAKE
#   write_protocol FILE DISTANCES ANGLES PRESET FRAMES
#                                 a protocol of DISTANCES × ANGLES ("4, 8, 12"), one preset,
#                                 emitter on, daylight, the calibrated sensor
fail() {
  echo "$NAME: $*" >&2
  exit 1
}
use_build() {
  BUILD=$(cd "${1:-$ROOT/build}" 2>/dev/null && pwd) || fail "no build directory ${1:-$ROOT/build}"
  APPS=$BUILD/apps
  shift
  local tool
  for tool in "$@"; do
    [ -x "$APPS/$tool" ] || fail "$APPS/$tool not built; run scripts/build.sh"
  done
}
use_snakemake() {
  PYTHON=$(sed -n 's/^DEPTHBIAS_PYTHON:[A-Z]*=//p' "$BUILD/CMakeCache.txt" 2>/dev/null || true)
  [ -x "${PYTHON:-}" ] || PYTHON=$ROOT/.venv/bin/python
  SNAKEMAKE=$(dirname "$PYTHON")/snakemake
  [ -x "$SNAKEMAKE" ] || fail "$SNAKEMAKE not found; run scripts/setup.sh"
}
write_protocol() {
  cat >"$1" <<PROTOCOL
protocol:
  distances_m: [$2]
  angles_deg: [$3]
  presets: [$4]
  emitters: ["on"]
  lights: [daylight]
  distance_is: range
  frames: $5
scene:
  camera_height_m: 1.0
  panel_center_height_m: 1.0
sensor: $ROOT/config/sensor_calibrated.yaml
PROTOCOL
}
