#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test tier (unit,
# ROS-side gtests, rostests with the real launch files), the static checks, the sanitizer pass
# and the fuzz pass. Exit status is non-zero when anything fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
date +"[stage %T] "$GMM_REPO/scripts/install_deps.sh""; "$GMM_REPO/scripts/install_deps.sh"
date +"[stage %T] "$GMM_REPO/scripts/check_core_deps.sh""; "$GMM_REPO/scripts/check_core_deps.sh"
date +"[stage %T] "$GMM_REPO/scripts/test_check_core_deps.sh""; "$GMM_REPO/scripts/test_check_core_deps.sh"
date +"[stage %T] "$GMM_REPO/scripts/check_format.sh""; "$GMM_REPO/scripts/check_format.sh"
date +"[stage %T] "$GMM_REPO/scripts/build.sh""; "$GMM_REPO/scripts/build.sh"
date +"[stage %T] "$GMM_REPO/scripts/build.sh""; "$GMM_REPO/scripts/build.sh" tests
gmm_source_ros
# run_tests executes every gtest and rostest; catkin_test_results then reports and sets status.
date +"[stage %T] run_tests"; make -C "$GMM_BUILD" --no-print-directory -j1 run_tests >"$GMM_WS/run_tests.log" 2>&1 || true
grep -E "^\[ *(RUN|OK|FAILED|SKIPPED|PASSED) *\]|SKIP|rostest|Ran [0-9]+ test" "$GMM_WS/run_tests.log" \
  | grep -vE "^\[ *(RUN|OK) *\]" || true
catkin_test_results --verbose "$GMM_BUILD/test_results" | tail -n 40
# The sanitizer pass: ASan+UBSan and TSan builds of the master-free gtests, run (about 9.5 min on
# 2 cores from a clean clone: ASan 7.5, TSan 2; scripts/run_sanitizers.sh). Its status counts
# after the reports.
sanitizers_ok=true
date +"[stage %T] "$GMM_REPO/scripts/run_sanitizers.sh""; "$GMM_REPO/scripts/run_sanitizers.sh" || sanitizers_ok=false
# The fuzz pass: libFuzzer targets of every parser of outside input, built with clang-14
# (ASan+UBSan), the reproducers of test/fuzz/regressions replayed, then 3 s of fuzzing per
# target here (GMM_FUZZ_TIME; scripts/run_fuzz.sh alone: 20 s; docs/fuzzing.md). Its status
# counts like the sanitizers'.
fuzz_ok=true
date +"[stage %T] fuzz"; GMM_FUZZ_TIME="${GMM_FUZZ_TIME:-3}" "$GMM_REPO/scripts/run_fuzz.sh" || fuzz_ok=false
date +"[stage %T] end"; catkin_test_results "$GMM_BUILD/test_results" >/dev/null
$sanitizers_ok && $fuzz_ok
