#!/usr/bin/env bash
# Configures and builds the package (a standalone catkin build of the repository root) into
# $GMM_WS (default .ws/ inside the repository). Extra arguments go to make (e.g. a target).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
mkdir -p "$GMM_BUILD"
# On CI (CI=true, a clean clone) the libraries compile in unity batches, as the sanitizer
# builds do (cmake/sanitize.cmake): each batch parses the ROS, PCL and Eigen headers once. A
# developer's build stays one source at a time (quicker rebuilds of one changed file); the
# choice is made when the build directory is first configured. GMM_UNITY=ON|OFF overrides it.
if [ "${CI:-}" = true ]; then unity_default=ON; else unity_default=OFF; fi
UNITY="${GMM_UNITY:-$unity_default}"
if [ ! -f "$GMM_BUILD/Makefile" ]; then
  cmake -S "$GMM_REPO" -B "$GMM_BUILD" \
    -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_UNITY_BUILD="$UNITY" \
    -DCATKIN_DEVEL_PREFIX="$GMM_DEVEL" \
    -DCMAKE_INSTALL_PREFIX="$GMM_WS/install" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DCATKIN_ENABLE_TESTING=ON >"$GMM_WS/cmake.log" 2>&1 || { cat "$GMM_WS/cmake.log"; exit 1; }
else
  # Re-configure (a few seconds) so that new sources and tests are picked up.
  cmake "$GMM_BUILD" >"$GMM_WS/cmake.log" 2>&1 || { cat "$GMM_WS/cmake.log"; exit 1; }
fi
JOBS="${GMM_JOBS:-$(nproc)}"
make -C "$GMM_BUILD" -j"$JOBS" --no-print-directory "$@"
