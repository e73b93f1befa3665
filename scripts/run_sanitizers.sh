#!/usr/bin/env bash
# The sanitizer pass of the test command (scripts/run_tests.sh calls it): two more builds of the
# package, each in its own build directory under $GMM_WS with -DGMM_SANITIZE (cmake/sanitize.cmake:
# -fsanitize=... -fno-omit-frame-pointer -O1 -g1 on every target), of the test binaries only
# (and the libraries they link and the two tools some of them run, build_map and map_info; not
# the other tools or the nodelets), then runs them:
#   asan  address,undefined: every gtest that needs no ROS master - test/unit (core, simulator),
#         test/ros (ROS glue) and test/tools (but those in scripts/sanitizer_skip.txt). The first
#         report fails the test (halt_on_error; UBSan aborts: -fno-sanitize-recover=undefined),
#         leaks included. The test command runs these tests only here, not in the Release build.
#         UBSan runs without its null, alignment, object-size and pointer-overflow checks
#         (cmake/sanitize.cmake says why).
#   tsan  thread: the tests that run threads of the core and simulator - the map server engine
#         (unit_chunk_engine_test, unit_chunk_engine_retry_test), the map builder
#         (unit_map_builder_test), the simulator (test/unit/sim), the task pool a match runs on
#         (unit_task_pool_test) and the parallel branch-and-bound (unit_grid_search_parallel_test).
#         The matcher's worker thread runs only in the rostests (ROS libraries are not
#         instrumented), so TSan does not see it.
#         False positives inside Embree and TBB are suppressed (scripts/tsan.supp says why).
# Logs: $GMM_WS/sanitizers/<asan|tsan>/<test>.log; a failing test's report is printed. Exit status
# non-zero when a build or a test fails. GMM_SANITIZERS selects the passes ("asan tsan" by default;
# empty: none); GMM_JOBS the parallel compile jobs and test runs (default: nproc);
# GMM_ASAN_CXX and GMM_TSAN_CXX the compilers (clang++-14 and g++ by default, see below);
# GMM_BUILD_ONLY=1 builds the passes' tests and runs none (scripts/run_tests.sh builds them
# beside the rostests, then runs this script again, whose builds are then up to date);
# GMM_TEST_RESULTS=<dir> writes the ASan pass's gtest XML reports there (run_tests.sh: the
# Release build's test_results, where these tests are not built).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
# shellcheck source=job_pool.sh
source "$(dirname "${BASH_SOURCE[0]}")/job_pool.sh"
SANITIZERS="${GMM_SANITIZERS-asan tsan}"
JOBS="${GMM_JOBS:-$(nproc)}"
LOGS="$GMM_WS/sanitizers"
# Compilers: Clang 14 builds the ASan pass in 5.5-6.5 min where GCC 12 took 8.8 (2 cores, clean);
# Clang 14's shared TSan runtime (needed by the shared libraries) crashes at start-up here, so
# the TSan pass uses GCC, the compiler of the main build.
ASAN_CXX="${GMM_ASAN_CXX:-clang++-14}"
TSAN_CXX="${GMM_TSAN_CXX:-g++}"
# The test binaries must load the sanitized libraries of their own build directory, not the main
# build's that the ROS environment (devel/setup.bash) puts on LD_LIBRARY_PATH: built from other
# headers, those gave stack-buffer-overflows. cmake/sanitize.cmake links with RPATH (searched
# before LD_LIBRARY_PATH); the workspace's entries are dropped here as well.
LD_LIBRARY_PATH="$(tr ':' '\n' <<<"${LD_LIBRARY_PATH:-}" | grep -v "^$GMM_WS" | paste -sd: || true)"
export LD_LIBRARY_PATH

# test_targets <build> <prefix:path>...: test targets named after the test files under each path
# (a directory or one file), as cmake/tests/*.cmake and cmake/tools/*.cmake name
# them (unit_<file>, ros_<file>, tools_<file>), that the build directory defines.
test_targets() {
  local build="$1"
  shift
  local defined
  defined="$(ninja -C "$build" -t targets all | sed -n 's/^\([A-Za-z0-9_]*\): phony$/\1/p')"
  local spec prefix dir name
  for spec in "$@"; do
    prefix="${spec%%:*}"
    dir="${spec#*:}"
    [ -e "$GMM_REPO/$dir" ] || continue
    while IFS= read -r name; do
      grep -qx "$prefix$name" <<<"$defined" && echo "$prefix$name"
    done < <(find "$GMM_REPO/$dir" -name '*_test.cpp' -printf '%f\n' | sed 's/\.cpp$//' | sort)
  done
  return 0
}

# Ninja, not make: CMake's top-level Makefile is .NOTPARALLEL, so make builds several goals (the
# test targets) one after the other, on one core; ninja builds them all in parallel.
configure() {
  local build="$1" sanitize="$2" cxx c
  cxx="$(command -v "$3")" || { echo "[sanitizers] no compiler $3" >&2; return 1; }
  c="$(command -v "$(sed 's/clang++/clang/; s/g++/gcc/' <<<"$(basename "$cxx")")")" || return 1
  # A directory of another generator or compiler (or an interrupted first configure) is started
  # afresh.
  if [ ! -f "$build/build.ninja" ] ||
    ! grep -qx "CMAKE_CXX_COMPILER:[A-Z]*=$cxx" "$build/CMakeCache.txt"; then
    rm -rf "$build"
  fi
  mkdir -p "$build"
  if [ ! -f "$build/build.ninja" ]; then
    cmake -S "$GMM_REPO" -B "$build" -G Ninja \
      -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_C_COMPILER="$c" \
      -DGMM_SANITIZE="$sanitize" \
      -DCATKIN_DEVEL_PREFIX="$build/devel" \
      -DCMAKE_INSTALL_PREFIX="$build/install" \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 \
      -DCATKIN_ENABLE_TESTING=ON >"$build/cmake.log" 2>&1 || { cat "$build/cmake.log"; return 1; }
  else
    cmake "$build" >"$build/cmake.log" 2>&1 || { cat "$build/cmake.log"; return 1; }
  fi
}

# first_slow: the test names of stdin, the SLOW ones first (in SLOW's order), then the rest.
first_slow() {
  local all t
  all="$(cat)"
  for t in "${SLOW[@]}"; do
    grep -xF "$t" <<<"$all" || true
  done
  grep -vxF -f <(printf '%s\n' "${SLOW[@]}") <<<"$all" || true
}

# The thread pass runs only these tests of a binary (GTEST_FILTER): its threaded ones, where the
# others would only add minutes under TSan (the global search's exhaustive comparisons).
declare -A TSAN_FILTER=([unit_global_search_test]="GlobalSearch.OnAPoolTheSameOptimumAsOneQueue")

# run_one <pass> <binary>: runs one gtest from the repository root (the tests' working
# directory), its output in the pass's log directory. With GMM_TEST_RESULTS set, the ASan pass
# also writes gtest's XML report there as gtest-<name>.xml (catkin's name for it), so that
# catkin_test_results counts these tests beside the Release build's.
run_one() {
  local pass="$1" binary="$2" name filter="" output=""
  name="$(basename "$binary")"
  [ "$pass" = tsan ] && filter="${TSAN_FILTER[$name]:-}"
  if [ "$pass" = asan ] && [ -n "${GMM_TEST_RESULTS:-}" ]; then
    output="xml:$GMM_TEST_RESULTS/gtest-$name.xml"
  fi
  if (cd "$GMM_REPO" && GTEST_FILTER="${filter:-*}" GTEST_OUTPUT="$output" "$binary") \
    >"$LOGS/$pass/$name.log" 2>&1; then
    echo "[sanitizers] $pass OK     $name"
  else
    echo "[sanitizers] $pass FAILED $name ($LOGS/$pass/$name.log):"
    # The sanitizer's report (or gtest's failures) and what led to it.
    grep -nE "ERROR: (Address|Leak|Thread)Sanitizer|WARNING: ThreadSanitizer|runtime error|SUMMARY|\[  FAILED  \]" \
      "$LOGS/$pass/$name.log" | head -n 20 || true
    tail -n 60 "$LOGS/$pass/$name.log"
    return 1
  fi
}

# run_pass <pass> <build> <test>...: the tests, JOBS at a time; returns the number that failed.
run_pass() {
  local pass="$1" build="$2"
  shift 2
  mkdir -p "$LOGS/$pass"
  rm -f "$LOGS/$pass"/*.log
  local failed=0
  run_pool "$JOBS" run_built_test "$@" || failed=$?
  return "$failed"
}
# run_built_test <test>: run_one for a test of the pass and build of the calling run_pass.
run_built_test() { run_one "$pass" "$build/devel/lib/gmm_localization/$1"; }

# pass <name> <-fsanitize list> <compiler> <test dir spec>...
pass() {
  local name="$1" sanitize="$2" cxx="$3"
  shift 3
  local build="$GMM_WS/$name" start=$SECONDS
  # (errexit does not apply inside a function called with ||: every step checks its status.)
  configure "$build" "$sanitize" "$cxx" || return 1
  local all targets skipped
  all="$(test_targets "$build" "$@")"
  mapfile -t targets < <(grep -vxF -f <(printf '%s\n' "${SKIP[@]}") <<<"$all" | first_slow | sed '/^$/d')
  skipped="$(grep -xF -f <(printf '%s\n' "${SKIP[@]}") <<<"$all" | paste -sd' ' || true)"
  if [ -n "$skipped" ]; then
    echo "[sanitizers] $name: not run: $skipped (the reasons: scripts/sanitizer_skip.txt)"
  fi
  if [ "${#targets[@]}" -eq 0 ]; then
    echo "[sanitizers] $name: no test targets found" >&2
    return 1
  fi
  echo "[sanitizers] $name ($sanitize, $cxx): building ${#targets[@]} tests in $build"
  ninja -C "$build" -j"$JOBS" "${targets[@]}" >"$build/build.log" 2>&1 ||
    { tail -n 80 "$build/build.log"; echo "[sanitizers] $name: build failed" >&2; return 1; }
  local built=$SECONDS
  if [ "${GMM_BUILD_ONLY:-0}" = 1 ]; then
    echo "[sanitizers] $name: built in $((built - start)) s (GMM_BUILD_ONLY: not run)"
    return 0
  fi
  local failed=0
  run_pass "$name" "$build" "${targets[@]}" || failed=$?
  echo "[sanitizers] $name: build $((built - start)) s, tests $((SECONDS - built)) s," \
    "$((${#targets[@]} - failed))/${#targets[@]} passed"
  [ "$failed" -eq 0 ]
}

# halt_on_error: the first report fails the test. Leaks are reported (LSan, part of ASan).
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:abort_on_error=0:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:print_summary=1"
# TSan's suppressions: false positives inside Embree and TBB (uninstrumented; scripts/tsan.supp
# says which and why). Races in the project's code are still reported. A log ends with the
# suppressions that matched, if any (print_suppressions).
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:print_summary=1:print_suppressions=1"
TSAN_OPTIONS+=":suppressions=$GMM_REPO/scripts/tsan.supp"

# Left out of the ASan pass (the names and reasons in scripts/sanitizer_skip.txt; the test
# command runs them in the Release build).
mapfile -t SKIP < <(grep -E '^[a-z]' "$GMM_REPO/scripts/sanitizer_skip.txt")
# The longest tests under the sanitizers, started first so that a pass does not end on one of
# them alone (clean 2-core run; ASan: registration and pipeline about 25 s, certificate 17 s,
# kitti_check 12 s, registration errors 10 s, the rest under 7 s; TSan: map builder 14 s, labels
# 9 s, chunk engine 8 s, INS 6 s, the rest under 5 s).
SLOW=(unit_registration_test unit_localizer_pipeline_test unit_match_certificate_test
  tools_kitti_check_register_test unit_registration_error_test unit_ekf_simulation_test
  unit_grid_search_test unit_map_builder_test unit_sim_labels_test unit_chunk_engine_test
  unit_sim_ins_test)

status=0
for s in $SANITIZERS; do
  case "$s" in
    asan)
      pass asan address,undefined "$ASAN_CXX" unit_:test/unit ros_:test/ros tools_:test/tools ||
        status=1
      ;;
    tsan)
      # The threaded tests: every simulator test (the ray caster and the runs use a thread pool),
      # the chunk engine's worker threads (serving, tile retries), the map builder's parallel fit,
      # the match's task pool, the search's parallel passes and the global search's queues.
      pass tsan thread "$TSAN_CXX" unit_:test/unit/sim unit_:test/unit/raster/chunk_engine_test.cpp \
        unit_:test/unit/raster/chunk_engine_retry_test.cpp \
        unit_:test/unit/mapping/map_builder_test.cpp unit_:test/unit/common/task_pool_test.cpp \
        unit_:test/unit/matching/grid_search_parallel_test.cpp \
        unit_:test/unit/matching/global_search_test.cpp || status=1
      ;;
    *) echo "[sanitizers] unknown pass '$s' (asan, tsan)" >&2; status=1 ;;
  esac
done
exit "$status"
