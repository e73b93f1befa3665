#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test tier (unit,
# ROS-side gtests, rostests with the real launch files), the static checks, the sanitizer pass
# and the fuzz pass. Exit status is non-zero when anything fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
"$GMM_REPO/scripts/install_deps.sh"
"$GMM_REPO/scripts/check_core_deps.sh"
"$GMM_REPO/scripts/test_check_core_deps.sh"
"$GMM_REPO/scripts/check_format.sh"
/usr/bin/python3 "$GMM_REPO/scripts/check_unity_names.py"
"$GMM_REPO/scripts/build.sh"
"$GMM_REPO/scripts/build.sh" tests
gmm_source_ros
# The sanitizer and fuzz builds (about 11 min of compiling on 2 cores from a clean clone) start
# now at the lowest CPU priority, beside the tests: the rostests replay drives in real time and
# leave about half of the CPU idle (58% over vehicle_replay and vehicle_bad_input), which the
# builds take without taking it from the tests (nice 19: about 1.5% of a core against a busy
# test process). Their passes below then find the builds up to date; a build that failed here
# fails again there, with its errors printed.
background_log="$GMM_WS/background_builds.log"
(
  nice -n 19 env GMM_BUILD_ONLY=1 "$GMM_REPO/scripts/run_sanitizers.sh" || true
  nice -n 19 env GMM_BUILD_ONLY=1 "$GMM_REPO/scripts/run_fuzz.sh" || true
) >"$background_log" 2>&1 &
background_builds=$!
# run_tests executes every gtest and rostest; catkin_test_results then reports and sets status.
make -C "$GMM_BUILD" --no-print-directory -j1 run_tests >"$GMM_WS/run_tests.log" 2>&1 || true
grep -E "^\[ *(RUN|OK|FAILED|SKIPPED|PASSED) *\]|SKIP|rostest|Ran [0-9]+ test" "$GMM_WS/run_tests.log" \
  | grep -vE "^\[ *(RUN|OK) *\]" || true
catkin_test_results --verbose "$GMM_BUILD/test_results" | tail -n 40
# The background builds' rest (alone on the CPU now, so their priority no longer matters).
echo "[run_tests] waiting for the sanitizer and fuzz builds started beside the tests"
wait "$background_builds" || true
grep -E "built in|failed" "$background_log" || true
# The sanitizer pass: ASan+UBSan and TSan builds of the master-free gtests (built above), run
# (scripts/run_sanitizers.sh). Its status counts after the reports.
sanitizers_ok=true
"$GMM_REPO/scripts/run_sanitizers.sh" || sanitizers_ok=false
# The fuzz pass: libFuzzer targets of every parser of outside input, built with clang-14
# (ASan+UBSan), the reproducers of test/fuzz/regressions replayed, then 3 s of fuzzing per
# target here (GMM_FUZZ_TIME; scripts/run_fuzz.sh alone: 20 s; docs/fuzzing.md). Its status
# counts like the sanitizers'.
fuzz_ok=true
GMM_FUZZ_TIME="${GMM_FUZZ_TIME:-3}" "$GMM_REPO/scripts/run_fuzz.sh" || fuzz_ok=false
catkin_test_results "$GMM_BUILD/test_results" >/dev/null
$sanitizers_ok && $fuzz_ok
