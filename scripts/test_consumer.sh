#!/usr/bin/env bash
# The installed package as another project sees it:
#   1. installs BUILD_DIR into a fresh prefix: cmake --install (BUILD_DIR/consumer-test/prefix),
#      or with --deb the Debian packages cpack -G DEB makes, unpacked (BUILD_DIR/consumer-deb/);
#   2. checks that no installed file names the source or build tree (the prefix is relocatable)
#      and, with --deb, that both packages declare their Debian dependencies;
#   3. builds tests/consumer/ against that prefix alone (find_package(depthbias)): the consumer
#      program and one translation unit per installed header, each header included on its own;
#   4. fits weights with the installed fit_bias, runs the consumer on a fixture bag, and checks the
#      corrected range it prints against the installed correct_depth's for the same depth and
#      off-axis angle (two paths through model::BiasModel that must agree).
#   bash scripts/test_consumer.sh BUILD_DIR [--deb]      (ctest runs both: label "package")
# Every failing step says which, on one line, and the script exits non-zero.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
fail() {
  echo "test_consumer: $*" >&2
  exit 1
}
[ $# -ge 1 ] && [ $# -le 2 ] || fail "usage: scripts/test_consumer.sh BUILD_DIR [--deb]"
[ -f "$1/CMakeCache.txt" ] || fail "$1 is not a configured build directory"
BUILD=$(cd "$1" && pwd)
DEB=0
if [ $# -eq 2 ]; then
  [ "$2" = "--deb" ] || fail "unknown argument '$2' (usage: test_consumer.sh BUILD_DIR [--deb])"
  DEB=1
fi
# A fixed place under the build directory, emptied first: the consumer's compilations then hit
# ccache from one run to the next.
if [ $DEB -eq 1 ]; then WORK=$BUILD/consumer-deb; else WORK=$BUILD/consumer-test; fi
rm -rf "$WORK"
mkdir -p "$WORK"

# 1. Install.
if [ $DEB -eq 1 ]; then
  command -v dpkg-deb >/dev/null 2>&1 || fail "dpkg-deb not found (Debian's dpkg)"
  cpack --config "$BUILD/CPackConfig.cmake" -G DEB -B "$WORK/cpack" >"$WORK/cpack.log" 2>&1 ||
    fail "cpack -G DEB failed, see $WORK/cpack.log"
  for package in depthbias depthbias-dev; do
    deb=$(ls "$WORK/cpack/${package}_"*.deb 2>/dev/null | head -1)
    [ -n "$deb" ] || fail "cpack made no ${package}_*.deb, see $WORK/cpack.log"
    dpkg-deb -x "$deb" "$WORK/root" || fail "dpkg-deb -x $deb failed"
    depends=$(dpkg-deb -f "$deb" Depends)
    case $package in
      depthbias) want="libpcl-common" ;;  # dpkg-shlibdeps found the tools' runtime libraries
      depthbias-dev) want="libpcl-dev" ;;
    esac
    [[ "$depends" == *"$want"* ]] || fail "$deb: Depends lacks $want: '$depends'"
    echo "test_consumer: $(basename "$deb"): $(stat -c %s "$deb") bytes," \
      "$(dpkg-deb -c "$deb" | grep -vc '/$') files"
  done
  PREFIX=$WORK/root/usr
else
  PREFIX=$WORK/prefix
  cmake --install "$BUILD" --prefix "$PREFIX" >"$WORK/install.log" 2>&1 ||
    fail "cmake --install $BUILD failed, see $WORK/install.log"
fi
[ -f "$PREFIX/lib/cmake/depthbias/depthbiasConfig.cmake" ] ||
  fail "no lib/cmake/depthbias/depthbiasConfig.cmake in the installed tree"

# 2. No path of the source or build tree (nor of the prefix itself) in any installed file. A
# sanitizer build embeds its sources' paths for its reports by design: not checked there.
if grep -q '^DEPTHBIAS_SANITIZE:BOOL=ON' "$BUILD/CMakeCache.txt" 2>/dev/null; then
  echo "test_consumer: sanitizer build: installed files may name the sources (not checked)"
elif leaks=$(grep -rlaF -e "$ROOT" -e "$BUILD" "$PREFIX"); then
  fail "installed files name the source or build tree: $(echo "$leaks" | tr '\n' ' ')"
fi

# 3. The consumer project, against the prefix only.
GENERATOR=()
command -v ninja >/dev/null 2>&1 && GENERATOR=(-G Ninja)
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$ROOT}
  LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# The headers of the packages are the files cmake --install puts: checked once, without --deb.
CHECK_HEADERS=ON
[ $DEB -eq 1 ] && CHECK_HEADERS=OFF
cmake -S "$ROOT/tests/consumer" -B "$WORK/build" "${GENERATOR[@]}" "${LAUNCHER[@]}" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$PREFIX" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
    -DCHECK_HEADERS=$CHECK_HEADERS >"$WORK/configure.log" 2>&1 ||
  fail "configuring tests/consumer against $PREFIX failed, see $WORK/configure.log"
if [ $CHECK_HEADERS = ON ]; then
  grep -q "depthbias headers to check:" "$WORK/configure.log" ||
    fail "tests/consumer found no installed headers to check"
fi
cmake --build "$WORK/build" -j "${JOBS:-2}" >"$WORK/build.log" 2>&1 ||
  fail "building tests/consumer (consumer or a header on its own) failed, see $WORK/build.log"
if [ $CHECK_HEADERS = ON ]; then
  echo "test_consumer: consumer built; $(grep -o 'depthbias headers to check: [0-9]*' \
    "$WORK/configure.log" | grep -o '[0-9]*$') installed headers compile on their own"
else
  echo "test_consumer: consumer built against the unpacked packages"
fi

# 4. Run it.
BIN=$PREFIX/bin
BAG=$ROOT/tests/data/bags/d455_depth_1mm.bag  # 64×48, High Accuracy, emitter on
"$BIN/fit_bias" --in "$ROOT/config/data/paper_d455_outdoor.csv" --out "$WORK/weights.yaml" \
    >"$WORK/fit_bias.log" 2>&1 || fail "installed fit_bias failed, see $WORK/fit_bias.log"
"$WORK/build/correct_cloud" "$BAG" "$WORK/weights.yaml" daylight >"$WORK/consumer.out" 2>&1 ||
  fail "correct_cloud failed: $(cat "$WORK/consumer.out")"
cat "$WORK/consumer.out"
value() { grep -o " $1=[^ ]*" "$WORK/consumer.out" | head -1 | cut -d= -f2; }
depth=$(value depth_m)
angle=$(value angle_deg)
range=$(value range_m)
corrected=$(value corrected_range_m)
[ -n "$depth" ] && [ -n "$angle" ] && [ -n "$corrected" ] ||
  fail "correct_cloud printed no 'pixel ... corrected_range_m=' line"
grep -q "scenario light=daylight preset=HA emitter=on" "$WORK/consumer.out" ||
  fail "correct_cloud did not read the bag's preset (HA) and emitter (on)"
grep -Eq "corrected=[1-9][0-9]* failed=0" "$WORK/consumer.out" ||
  fail "correct_cloud corrected no point, or some failed"

# The same depth and angle through the installed correct_depth: corrected_m must be the range.
printf '%s\n%s\n' \
  "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,hole_rate_pct,valid_pct" \
  "consumer,daylight,on,HA,$range,$angle,1,$depth,$depth,0,0,100" >"$WORK/point.csv"
"$BIN/correct_depth" --weights "$WORK/weights.yaml" --in "$WORK/point.csv" \
    --out "$WORK/point_corrected.csv" >"$WORK/correct_depth.log" 2>&1 ||
  fail "installed correct_depth failed, see $WORK/correct_depth.log"
expected=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "corrected_m") c = i }
                    NR == 2 { print $c }' "$WORK/point_corrected.csv")
[ -n "$expected" ] || fail "no corrected_m in $WORK/point_corrected.csv"
# The cloud holds floats: agreement to 1e-5 m (float rounding at a few metres is ~5e-7 m). The
# fixture's point is near (4.4 m), where the model's near guard may leave the reading as it is:
# what is checked is that the consumer and correct_depth give the same answer.
awk -v a="$corrected" -v b="$expected" 'BEGIN {
  d = a - b; if (d < 0) d = -d
  if (d > 1e-5) exit 1 }' ||
  fail "corrected range $corrected m differs from correct_depth's $expected m (raw range $range m)"
echo "test_consumer: corrected range $corrected m = correct_depth's $expected m (raw $range m): ok"
