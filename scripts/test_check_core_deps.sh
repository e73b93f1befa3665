#!/usr/bin/env bash
# Shows that scripts/check_core_deps.sh fails on what it forbids: on a copy of the core and the
# simulator it must pass as it is, then fail on (1) a back edge between stage folders (the
# filter including the localization policy), (2) a ROS include in the core, (3) the simulator
# including a matching header, (4) a file outside a stage folder. Run by scripts/run_tests.sh.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
check="$repo/scripts/check_core_deps.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

fresh_copy() {
  rm -rf "$work/tree"
  mkdir -p "$work/tree/include/gmm_localization" "$work/tree/src"
  cp -r "$repo/include/gmm_localization/core" "$repo/include/gmm_localization/sim" \
    "$work/tree/include/gmm_localization/"
  cp -r "$repo/src/core" "$repo/src/sim" "$work/tree/src/"
}

expect_fail() {
  local what="$1"
  if "$check" "$work/tree" >"$work/out" 2>&1; then
    echo "test_check_core_deps: FAILED: the check passed with $what" >&2
    exit 1
  fi
  echo "test_check_core_deps: rejects $what: $(grep -m1 'check_core_deps:' "$work/out")"
}

fresh_copy
"$check" "$work/tree" >/dev/null || { echo "test_check_core_deps: FAILED: the clean tree fails" >&2; exit 1; }

fresh_copy
sed -i '0,/^#include "gmm_localization/s//#include "gmm_localization\/core\/localization\/match_policy.h"\n&/' \
  "$work/tree/include/gmm_localization/core/filter/ekf_state.h"
expect_fail "a back edge (filter -> localization)"

fresh_copy
echo '#include <ros/ros.h>' >>"$work/tree/src/core/raster/rasterizer.cpp"
expect_fail "a ROS include in the core"

fresh_copy
echo '#include "gmm_localization/core/matching/scan_filter.h"' >>"$work/tree/src/sim/town.cpp"
expect_fail "the simulator including a matching header"

fresh_copy
touch "$work/tree/include/gmm_localization/core/loose.h"
expect_fail "a header outside a stage folder"
echo "test_check_core_deps: 5 cases passed"
