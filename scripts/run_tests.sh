#!/usr/bin/env bash
# The README's test command: installs what is missing, runs the static checks, builds, and runs
# every test once - the master-free gtests (unit, ROS-side, tools) in the ASan+UBSan build, the
# rostests with the real launch files in the Release build - then TSan over the threaded tests
# and the fuzz pass. Exit status is non-zero when anything fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
"$GMM_REPO/scripts/install_deps.sh"
"$GMM_REPO/scripts/check_core_deps.sh"
"$GMM_REPO/scripts/test_check_core_deps.sh"
"$GMM_REPO/scripts/check_format.sh"
/usr/bin/python3 "$GMM_REPO/scripts/check_unity_names.py"
"$GMM_REPO/scripts/build.sh"
gmm_source_ros
# The sanitizer and fuzz builds (about 10 min of compiling on 2 cores from a clean clone) start
# now at the lowest CPU priority, beside the Release test build and the tests: the rostests
# replay drives in real time and leave about half of the CPU idle (58% over vehicle_replay and
# vehicle_bad_input), which the builds take without taking it from the tests (nice 19: about
# 1.5% of a core against a busy test process). Their passes below then find the builds up to
# date; a build that failed here fails again there, with its errors printed.
background_log="$GMM_WS/background_builds.log"
(
  nice -n 19 env GMM_BUILD_ONLY=1 "$GMM_REPO/scripts/run_sanitizers.sh" || true
  nice -n 19 env GMM_BUILD_ONLY=1 "$GMM_REPO/scripts/run_fuzz.sh" || true
) >"$background_log" 2>&1 &
background_builds=$!
# Every test is compiled and run once: the master-free gtests (test/unit, test/ros, test/tools)
# in the ASan+UBSan pass below, the rest here in the Release build (gmm_release_tests: the
# rostests with the real launch files, the roslaunch checks, and the gtests that
# scripts/sanitizer_skip.txt keeps out of the ASan pass, with the reasons). Their reports go to
# the same test_results, which catkin_test_results sums at the end.
"$GMM_REPO/scripts/build.sh" gmm_release_tests
results="$GMM_BUILD/test_results"
rm -rf "$results/gmm_localization"
mkdir -p "$results/gmm_localization"
release_runs=(run_tests_gmm_localization_rostest run_tests_gmm_localization_roslaunch-check)
while IFS= read -r t; do
  release_runs+=("run_tests_gmm_localization_gtest_$t")
done < <(grep -E '^[a-z]' "$GMM_REPO/scripts/sanitizer_skip.txt")
make -C "$GMM_BUILD" --no-print-directory -j1 "${release_runs[@]}" >"$GMM_WS/run_tests.log" 2>&1 ||
  true
grep -E "^\[ *(RUN|OK|FAILED|SKIPPED|PASSED) *\]|SKIP|rostest|Ran [0-9]+ test" "$GMM_WS/run_tests.log" \
  | grep -vE "^\[ *(RUN|OK) *\]" || true
# The background builds' rest (alone on the CPU now, so their priority no longer matters).
echo "[run_tests] waiting for the sanitizer and fuzz builds started beside the tests"
wait "$background_builds" || true
grep -E "built in|failed" "$background_log" || true
# The sanitizer pass: ASan+UBSan over every master-free gtest (their XML reports beside the
# Release build's) and TSan over the threaded ones (scripts/run_sanitizers.sh). Its status
# counts after the reports.
sanitizers_ok=true
GMM_TEST_RESULTS="$results/gmm_localization" "$GMM_REPO/scripts/run_sanitizers.sh" ||
  sanitizers_ok=false
# The fuzz pass: libFuzzer targets of every parser of outside input, built with clang-14
# (ASan+UBSan), the reproducers of test/fuzz/regressions replayed, then 3 s of fuzzing per
# target here (GMM_FUZZ_TIME; scripts/run_fuzz.sh alone: 20 s; docs/fuzzing.md). Its status
# counts like the sanitizers'.
fuzz_ok=true
GMM_FUZZ_TIME="${GMM_FUZZ_TIME:-3}" "$GMM_REPO/scripts/run_fuzz.sh" || fuzz_ok=false
# Every test's report: the Release build's and the ASan pass's.
catkin_test_results --verbose "$results" | tail -n 40
catkin_test_results "$results" >/dev/null
$sanitizers_ok && $fuzz_ok
