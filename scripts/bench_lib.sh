# Helpers of the bench_*.sh scripts (sourced, after set -euo pipefail and their ERR trap).
# Under set -e a command failing inside $(...) ends the script only when the $(...) is assigned;
# given as an argument (echo "$(...)", printf ... "$(...)") its failure is lost and an empty or
# wrong figure printed. So every figure is assigned first, then printed. And a $(...) runs
# without set -e unless inherit_errexit is on: a failing command before the last one of a
# function called as $(f) (bench_machine's nproc or /proc/loadavg) would go on and print a
# figure with a hole in it; with it, the assignment fails and the caller's ERR trap names it.
shopt -s inherit_errexit
# And the ERR trap is not inherited by functions unless errtrace is on: a command failing inside
# a function called on its own line (bench_obstacle_detector.sh's pcl_in, its sed) would end the
# script under set -e without the trap's line. With it the trap names the failing command there,
# and again at the assignment of a $(f) that failed.
set -E

best() { sort -g | head -1; }

# bench_positive_int NAME VALUE: ends the script, naming it, unless VALUE is a whole number >= 1.
bench_positive_int() {
  [[ "$2" =~ ^[1-9][0-9]*$ ]] ||
    { echo "$BENCH: $1 must be a whole number >= 1, not '$2'" >&2; exit 1; }
}

# The machine as a line: cores, CPU model (where /proc/cpuinfo names one), load.
bench_machine() {
  local cores model load
  cores=$(nproc)
  model=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs) || model="CPU model unknown"
  load=$(cut -d' ' -f1-3 /proc/loadavg)
  echo "$cores cores, $model, load $load"
}

# bench_ratio A B: A / B, failing (naming them) unless both are numbers and B > 0.
bench_ratio() {
  awk -v a="$1" -v b="$2" -v who="$BENCH" 'BEGIN {
    if (a !~ /^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$/ || b !~ /^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$/ || b <= 0) {
      printf "%s: cannot divide %s by %s\n", who, a, b > "/dev/stderr"; exit 1
    }
    printf "%.6g\n", a / b }'
}
