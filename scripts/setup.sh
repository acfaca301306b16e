#!/usr/bin/env bash
# Installs everything depthbias needs on a fresh Debian 12 machine: the C++ toolchain and
# libraries from Debian's packages, and the Python packages the fixture, check and benchmark
# scripts use. Safe to run again: it installs only what is missing.
set -euo pipefail

DEB_PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config git
  libeigen3-dev libpcl-dev libopencv-dev libceres-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev
  librosbag-storage-dev libroscpp-core-dev libsensor-msgs-dev pluginlib-dev
  libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
  libroslz4-dev libbz2-dev
  libusb-1.0-0 python3 python3-pip
)
# pyrealsense2 2.56.5 is the last release whose recorder writes ROS1 .bag files.
PY_PACKAGES=(pyrealsense2==2.56.5.9235 numpy)

missing=()
for p in "${DEB_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

PY=${PYTHON:-python3}
py_missing=()
for spec in "${PY_PACKAGES[@]}"; do
  name=${spec%%==*}
  want=${spec#*==}
  have=$($PY -m pip show "$name" 2>/dev/null | awk '/^Version:/{print $2}')
  if [ "$spec" = "$name" ]; then
    [ -n "$have" ] || py_missing+=("$spec")
  else
    [ "$have" = "$want" ] || py_missing+=("$spec")
  fi
done
if [ ${#py_missing[@]} -gt 0 ]; then
  echo "setup: pip installing ${py_missing[*]}"
  $PY -m pip install -q --disable-pip-version-check --root-user-action=ignore "${py_missing[@]}"
fi

# Optional benchmark dependency: Open3D for the plain-Python peer of
# scripts/bench_panel_extract.py, which installs it itself when missing. Not needed by the tests;
# WITH_BENCH=1 installs it here.
if [ "${WITH_BENCH:-0}" = "1" ] && ! $PY -c "import open3d" 2>/dev/null; then
  echo "setup: pip installing open3d (benchmark only)"
  $PY -m pip install -q --disable-pip-version-check --root-user-action=ignore open3d
fi
