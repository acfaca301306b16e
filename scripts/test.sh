#!/usr/bin/env bash
# The test command: installs what is missing, builds, and runs the whole GoogleTest suite under
# ctest. SANITIZE=1 builds with ASan + UBSan into build-asan/ instead.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# What workflow_slurm needs (SLURM, munge, MariaDB, Snakemake's SLURM executor) is installed here,
# before any test starts, and never by a test: a package half-written into .venv while another
# test's Snakemake starts a job fails that job (the executor plugins are imported at start-up).
# The SLURM test needs root; elsewhere it is skipped, and so is this.
if [ "$(id -u)" -eq 0 ]; then
  WITH_SLURM=1 bash scripts/setup.sh ||
    echo "test: SLURM or its executor not installed (above); workflow_slurm will be skipped" >&2
fi
if [ "${SANITIZE:-0}" = "1" ]; then
  export BUILD_DIR=${BUILD_DIR:-build-asan} BUILD_TYPE=RelWithDebInfo
  bash scripts/build.sh -DDEPTHBIAS_SANITIZE=ON
  export ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
else
  export BUILD_DIR=${BUILD_DIR:-build}
  bash scripts/build.sh
fi
# Tests run side by side on one machine and one .venv: none may install or remove a package. The
# packages before and after the run are compared, so a test that does fails every run, not only
# when another test happens to start beside it.
VENV_PY=${DEPTHBIAS_VENV:-$PWD/.venv}/bin/python
installed() {
  dpkg-query -W -f='deb ${Package} ${Version}\n' 2>/dev/null
  "$VENV_PY" -m pip list --disable-pip-version-check --format=freeze 2>/dev/null | sed 's/^/pip /'
}
before=$(installed)
status=0
(cd "$BUILD_DIR" && ctest --output-on-failure -j "${JOBS:-$(nproc)}" --timeout 600) || status=$?
changed=$(diff <(echo "$before") <(installed) | grep '^[<>]' || true)
if [ -n "$changed" ]; then
  echo "test: packages changed while the tests ran (< before, > after); a test installs or" \
    "removes packages, which another test running beside it may see half-written:" >&2
  echo "$changed" >&2
  exit 1
fi
exit $status
