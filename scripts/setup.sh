#!/usr/bin/env bash
# Installs everything depthbias needs on a fresh Debian 12 machine:
#   1. the C++ toolchain and libraries, from Debian's packages (apt-get, as root or with sudo);
#   2. the project's Python environment, .venv/ at the repository's root, made by Debian's own
#      python3 whatever python3 comes first on PATH, from the pinned scripts/requirements.txt.
# Scripts and tests use .venv/bin/python only, never a global interpreter.
# Safe to run again: it installs only what is missing. Every step that fails says which step it
# was and what to do, on one line, and the script exits non-zero.
# Environment: WITH_BENCH=1 also installs the benchmark-only peer (Open3D) into .venv.
#   WITH_SLURM=1 also installs SLURM with munge and MariaDB (its accounting database) from Debian,
#   and the workflow's SLURM executor (workflow/requirements-cluster.txt) into .venv: what
#   scripts/test_workflow_slurm.sh needs to run the workflow on a single-node SLURM.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
VENV=${DEPTHBIAS_VENV:-$ROOT/.venv}
REQUIREMENTS=$ROOT/scripts/requirements.txt

DEB_PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config git file dpkg-dev
  libeigen3-dev libpcl-dev libopencv-dev libceres-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev
  librosbag-storage-dev libroscpp-core-dev libsensor-msgs-dev pluginlib-dev
  libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
  libroslz4-dev libbz2-dev
  libzstd-dev liblz4-dev libsqlite3-dev zlib1g-dev
  clang libclang-rt-14-dev
  libusb-1.0-0 python3 python3-venv python3-dev
)
SLURM_PACKAGES=(slurm-wlm slurmdbd munge mariadb-server)
[ "${WITH_SLURM:-0}" = "1" ] && DEB_PACKAGES+=("${SLURM_PACKAGES[@]}")

fail() {  # fail STEP WHAT-TO-DO
  echo "setup: step '$1' failed: $2" >&2
  exit 1
}

# --- 1. Debian packages -------------------------------------------------------------------------
missing=()
for p in "${DEB_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null 2>&1 ||
      fail "apt packages" "not root and no sudo; as root run: apt-get install ${missing[*]}"
    SUDO="sudo"
  fi
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq >/tmp/depthbias-apt-update.log 2>&1 ||
    fail "apt-get update" "see /tmp/depthbias-apt-update.log (network or apt sources?)"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
      "${missing[@]}" >/tmp/depthbias-apt-install.log 2>&1 ||
    fail "apt-get install" "see /tmp/depthbias-apt-install.log; run: apt-get install ${missing[*]}"
fi

# --- 2. The project's Python environment --------------------------------------------------------
# Debian's interpreter, not the first python3 on PATH (a pyenv build, another project's venv):
# the venv must not depend on what a user's shell happens to hold.
BASE_PY=${DEPTHBIAS_BASE_PYTHON:-/usr/bin/python3}
[ -x "$BASE_PY" ] || fail "python" "$BASE_PY not found; install Debian's python3 and python3-venv"
[ -f "$REQUIREMENTS" ] || fail "requirements" "$REQUIREMENTS is missing from the checkout"

PY=$VENV/bin/python
if [ -e "$VENV" ] && ! "$PY" -c "import sys" >/dev/null 2>&1; then
  echo "setup: $VENV is broken (its interpreter does not start); making it again"
  rm -rf "$VENV" || fail "venv" "cannot remove the broken $VENV; remove it by hand"
fi
if [ ! -e "$VENV" ]; then
  echo "setup: making the project's Python environment in $VENV"
  "$BASE_PY" -m venv "$VENV" >/tmp/depthbias-venv.log 2>&1 ||
    fail "venv" "'$BASE_PY -m venv $VENV' failed, see /tmp/depthbias-venv.log (python3-venv installed?)"
fi

# The requirements are installed when the file changed since the last successful install.
STAMP=$VENV/.depthbias-requirements
want_sum=$(sha256sum "$REQUIREMENTS" | cut -d' ' -f1)
if [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$want_sum" ]; then
  echo "setup: installing scripts/requirements.txt into $VENV"
  "$PY" -m pip install -q --disable-pip-version-check -r "$REQUIREMENTS" \
      >/tmp/depthbias-pip.log 2>&1 ||
    fail "pip install" "see /tmp/depthbias-pip.log (PyPI reachable? pins in scripts/requirements.txt)"
  echo "$want_sum" > "$STAMP"
fi
# A check that the pinned recorder is the one the environment holds (its import needs libusb).
"$PY" -c "import pyrealsense2, numpy" >/tmp/depthbias-import.log 2>&1 ||
  fail "python imports" "pyrealsense2/numpy do not import in $VENV, see /tmp/depthbias-import.log"

# Optional benchmark dependency: Open3D for the plain-Python peer of
# scripts/bench_panel_extract.py. Not needed by the tests.
if [ "${WITH_BENCH:-0}" = "1" ] && ! "$PY" -c "import open3d" >/dev/null 2>&1; then
  echo "setup: installing open3d into $VENV (benchmark only)"
  "$PY" -m pip install -q --disable-pip-version-check open3d >/tmp/depthbias-pip-bench.log 2>&1 ||
    fail "pip install open3d" "see /tmp/depthbias-pip-bench.log"
fi

# Optional: the workflow's SLURM executor plugin, when the file changed since its last install.
CLUSTER_REQUIREMENTS=$ROOT/workflow/requirements-cluster.txt
CLUSTER_STAMP=$VENV/.depthbias-requirements-cluster
if [ "${WITH_SLURM:-0}" = "1" ]; then
  want_sum=$(sha256sum "$CLUSTER_REQUIREMENTS" | cut -d' ' -f1)
  if [ ! -f "$CLUSTER_STAMP" ] || [ "$(cat "$CLUSTER_STAMP")" != "$want_sum" ]; then
    echo "setup: installing workflow/requirements-cluster.txt into $VENV"
    "$PY" -m pip install -q --disable-pip-version-check -r "$CLUSTER_REQUIREMENTS" \
        >/tmp/depthbias-pip-cluster.log 2>&1 ||
      fail "pip install (cluster)" "see /tmp/depthbias-pip-cluster.log"
    echo "$want_sum" > "$CLUSTER_STAMP"
  fi
fi
exit 0
