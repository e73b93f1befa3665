#!/usr/bin/env bash
# Installs the Debian bookworm packages this project builds, tests and runs with.
# Idempotent: does nothing when everything is already installed.
set -euo pipefail
PACKAGES=(
  build-essential cmake git ninja-build
  ros-base-dev catkin libnodeletlib-dev libnodelet-dev libnodeletlib-tools pluginlib-dev
  libpcl-ros-dev libpcl-conversions-dev libpcl-dev libtf2-ros-dev libtf2-eigen-dev
  libtf2-geometry-msgs-dev libtf2-sensor-msgs-dev librosbag-dev librostest-dev
  libdiagnostic-msgs-dev libnav-msgs-dev libstd-srvs-dev libvisualization-msgs-dev
  ros-message-generation
  libdiagnostic-updater-dev libdiagnostic-aggregator-dev libdiagnostic-aggregator-tools
  rosdiagnostic catkin-lint rosbash
  python3-roslaunch python3-rostest python3-rosbag python3-rostopic python3-numpy
  python3-matplotlib
  python3-std-msgs python3-geometry-msgs python3-sensor-msgs python3-nav-msgs
  python3-diagnostic-msgs python3-tf2-msgs python3-visualization-msgs
  libeigen3-dev libyaml-cpp-dev zlib1g-dev libgtest-dev libbenchmark-dev libtbb-dev libembree-dev
  libgeographiclib-dev
  rviz xvfb imagemagick clang-format
  clang-14 libclang-rt-14-dev
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "[install_deps] all ${#PACKAGES[@]} packages present"
  exit 0
fi
echo "[install_deps] installing ${#missing[@]} packages: ${missing[*]}"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "[install_deps] done"
