#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz with clang into build-fuzz/ (every library
# instrumented, ASan + UBSan) and runs each on a scratch copy of its committed corpus
# tests/fuzz/corpus/<target>/ (the committed corpus is never changed; --merge adds the new inputs
# that reach new code to it, minimized). Any crash, sanitizer report, leak, timeout (> 10 s for
# one input) or memory blow-up (> 2 GB) is a finding: its input is kept in build-fuzz/artifacts/
# and the script exits 1.
#   bash scripts/fuzz.sh [--seconds N] [--merge] [--build-only] [TARGET...]
#   bash scripts/fuzz.sh --smoke [TARGET...]
# Default: open-ended fuzzing, every target for N seconds (15) from a new random seed each run:
# for finding bugs, never for a gate. --smoke is the gate (the ctest fuzz_smoke): every input of
# the committed corpus, then a fixed number of mutations from a fixed seed, so that two runs of
# the same code execute the same inputs and a failure is a regression, never bad luck.
# Prints per target the executions, the time and the findings, then "N passed, N failed".
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SECONDS_EACH=15
SMOKE=0
SMOKE_SEED=20261124  # fixed: the smoke run executes the same inputs every time
SMOKE_RUNS=30000     # mutations per target after the corpus (bag_reader: a tenth)
MERGE=0
BUILD_ONLY=0
TARGETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) SECONDS_EACH=$2; shift 2 ;;
    --smoke) SMOKE=1; shift ;;
    --merge) MERGE=1; shift ;;
    --build-only) BUILD_ONLY=1; shift ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) TARGETS+=("$1"); shift ;;
  esac
done
[ ${#TARGETS[@]} -gt 0 ] ||
  TARGETS=(bag_reader mcap metrics_csv manifest config_yaml weights_yaml sim_yaml)

command -v clang++ >/dev/null 2>&1 ||
  { echo "fuzz: clang++ not found; run scripts/setup.sh (clang, libclang-rt-14-dev)" >&2; exit 2; }
BUILD=${FUZZ_BUILD_DIR:-$ROOT/build-fuzz}
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$ROOT}
mkdir -p "$BUILD"
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DDEPTHBIAS_FUZZ=ON -DDEPTHBIAS_BUILD_TESTS=OFF \
    >"$BUILD/configure.log" 2>&1 ||
  { echo "fuzz: cmake failed, see $BUILD/configure.log" >&2; exit 2; }
# Only the targets asked for (each links only the libraries it fuzzes).
cmake --build "$BUILD" -j "${JOBS:-$(nproc)}" --target "${TARGETS[@]/#/fuzz_}" \
    >"$BUILD/build.log" 2>&1 ||
  { tail -20 "$BUILD/build.log" >&2; echo "fuzz: build failed, see $BUILD/build.log" >&2; exit 2; }
[ "$BUILD_ONLY" = 1 ] && exit 0

ART=$BUILD/artifacts
mkdir -p "$ART"
# Leaks are findings too; a process-wide leak check at exit would also report the libraries'
# own one-time allocations, so libFuzzer's per-input check is the one used.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
passed=0
failed=0
for t in "${TARGETS[@]}"; do
  bin=$BUILD/tests/fuzz/fuzz_$t
  corpus=$ROOT/tests/fuzz/corpus/$t
  [ -x "$bin" ] || { echo "fuzz: no target fuzz_$t" >&2; failed=$((failed + 1)); continue; }
  scratch=$(mktemp -d "${TMPDIR:-/tmp}/depthbias-fuzz-$t.XXXXXX")
  max_len=8192
  [ "$t" = bag_reader ] && max_len=65536
  log=$BUILD/fuzz_$t.log
  if [ "$SMOKE" = 1 ]; then
    runs_each=$SMOKE_RUNS
    case "$t" in bag_reader | mcap) runs_each=$((SMOKE_RUNS / 10)) ;; esac
    how=(-seed=$SMOKE_SEED -runs=$runs_each -reload=0)
    # Addresses reach the mutations through the compared values libFuzzer records: without
    # address randomization the same seed gives the same inputs.
    launch=(setarch "$(uname -m)" --addr-no-randomize)
    "${launch[@]}" true 2>/dev/null || launch=()  # where personality() is not allowed
  else
    how=(-max_total_time="$SECONDS_EACH")
    launch=()
  fi
  "${launch[@]}" "$bin" "${how[@]}" -timeout=10 -rss_limit_mb=2048 -max_len=$max_len \
      -print_final_stats=1 -artifact_prefix="$ART/$t-" "$scratch" "$corpus" >"$log" 2>&1
  rc=$?
  runs=$(grep -o 'stat::number_of_executed_units:[[:space:]]*[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  secs=$(grep -o 'Done [0-9]* runs in [0-9]* second' "$log" | grep -o 'in [0-9]*' | grep -o '[0-9]*')
  new=$(grep -o 'stat::new_units_added:[[:space:]]*[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*')
  if [ $rc -eq 0 ]; then
    echo "fuzz_$t: ${runs:-?} executions in ${secs:-?} s, coverage ${cov:-?} edges, ${new:-0} new inputs, 0 findings"
    passed=$((passed + 1))
    if [ "$MERGE" = 1 ]; then
      "$bin" -merge=1 -max_len=$max_len "$corpus" "$scratch" >>"$log" 2>&1
    fi
  else
    echo "fuzz_$t: FINDING after ${runs:-?} executions (exit $rc); input in $ART/$t-*, log $log"
    grep -m3 -E 'ERROR|SUMMARY|deadly signal' "$log"
    failed=$((failed + 1))
  fi
  rm -rf "$scratch"
done
echo "fuzz: $passed passed, $failed failed"
[ $failed -eq 0 ]
