#!/usr/bin/env bash
# The sanitizer pass of the test command (scripts/run_tests.sh calls it): two more builds of the
# package, each in its own build directory under $GMM_WS with -DGMM_SANITIZE (cmake/sanitize.cmake:
# -fsanitize=... -fno-omit-frame-pointer -O1 -g1 on every target), of the test binaries only
# (and the libraries they link, not the tools' executables or the nodelets), then runs them:
#   asan  address,undefined: every gtest that needs no ROS master - test/unit (core, simulator),
#         test/ros (ROS glue) and test/tools. The first report fails the test (halt_on_error;
#         UBSan aborts: -fno-sanitize-recover=undefined), leaks included.
#   tsan  thread: the tests that run threads of the core and simulator - the map server engine
#         (unit_chunk_engine_test), the map builder (unit_map_builder_test) and the simulator
#         (test/unit/sim). The matcher's worker thread runs only in the rostests (ROS libraries are
#         not instrumented), so TSan does not see it.
# Logs: $GMM_WS/sanitizers/<asan|tsan>/<test>.log; a failing test's report is printed. Exit status
# non-zero when a build or a test fails. GMM_SANITIZERS selects the passes ("asan tsan" by default;
# empty: none); GMM_JOBS the parallel compile jobs and test runs (default: nproc).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
SANITIZERS="${GMM_SANITIZERS-asan tsan}"
JOBS="${GMM_JOBS:-$(nproc)}"
LOGS="$GMM_WS/sanitizers"

# test_targets <build> <prefix:path>...: test targets named after the test files under each path
# (a directory or one file), as cmake/tests/*.cmake and cmake/tools/*.cmake name
# them (unit_<file>, ros_<file>, tools_<file>), that the build directory defines.
test_targets() {
  local build="$1"
  shift
  local defined
  defined="$(make -C "$build" --no-print-directory help | sed -n 's/^\.\.\. \([A-Za-z0-9_]*\).*/\1/p')"
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

configure() {
  local build="$1" sanitize="$2"
  mkdir -p "$build"
  if [ ! -f "$build/Makefile" ]; then
    cmake -S "$GMM_REPO" -B "$build" \
      -DCMAKE_BUILD_TYPE=Release \
      -DGMM_SANITIZE="$sanitize" \
      -DCATKIN_DEVEL_PREFIX="$build/devel" \
      -DCMAKE_INSTALL_PREFIX="$build/install" \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 \
      -DCATKIN_ENABLE_TESTING=ON >"$build/cmake.log" 2>&1 || { cat "$build/cmake.log"; return 1; }
  else
    cmake "$build" >"$build/cmake.log" 2>&1 || { cat "$build/cmake.log"; return 1; }
  fi
}

# run_one <pass> <binary>: runs one gtest from the repository root (the tests' working
# directory), its output in the pass's log directory.
run_one() {
  local pass="$1" binary="$2" name
  name="$(basename "$binary")"
  if (cd "$GMM_REPO" && "$binary") >"$LOGS/$pass/$name.log" 2>&1; then
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
  local failed=0 running=0 t
  for t in "$@"; do
    run_one "$pass" "$build/devel/lib/gmm_localization/$t" &
    running=$((running + 1))
    if [ "$running" -ge "$JOBS" ]; then
      wait -n || failed=$((failed + 1))
      running=$((running - 1))
    fi
  done
  while [ "$running" -gt 0 ]; do
    wait -n || failed=$((failed + 1))
    running=$((running - 1))
  done
  return "$failed"
}

# pass <name> <-fsanitize list> <test dir spec>...
pass() {
  local name="$1" sanitize="$2"
  shift 2
  local build="$GMM_WS/$name" start=$SECONDS
  # (errexit does not apply inside a function called with ||: every step checks its status.)
  configure "$build" "$sanitize" || return 1
  local targets
  mapfile -t targets < <(test_targets "$build" "$@" | grep -vxF -f <(printf '%s\n' "${SKIP[@]}"))
  if [ "${#targets[@]}" -eq 0 ]; then
    echo "[sanitizers] $name: no test targets found" >&2
    return 1
  fi
  echo "[sanitizers] $name ($sanitize): building ${#targets[@]} tests in $build"
  make -C "$build" -j"$JOBS" --no-print-directory "${targets[@]}" >"$build/make.log" 2>&1 ||
    { tail -n 80 "$build/make.log"; echo "[sanitizers] $name: build failed" >&2; return 1; }
  local built=$SECONDS
  local failed=0
  run_pass "$name" "$build" "${targets[@]}" || failed=$?
  echo "[sanitizers] $name: build $((built - start)) s, tests $((SECONDS - built)) s," \
    "$((${#targets[@]} - failed))/${#targets[@]} passed"
  [ "$failed" -eq 0 ]
}

# halt_on_error: the first report fails the test. Leaks are reported (LSan, part of ASan).
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:abort_on_error=0:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:print_summary=1"
# Embree builds its BVH on TBB worker threads, and both libraries are not instrumented: TSan sees
# their allocations and locks only in part and reports races inside them (false positives). Calls
# from these two libraries are not intercepted, nor memcmp (Embree's TBB threads compare strings
# through libstdc++, which called_from_lib cannot attribute); races in the project's code are
# still reported.
mkdir -p "$LOGS"
printf '%s\n' "called_from_lib:libembree3.so" "called_from_lib:libtbb.so" >"$LOGS/tsan.supp"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:print_summary=1:intercept_memcmp=0"
TSAN_OPTIONS+=":suppressions=$LOGS/tsan.supp"

# Left out of the ASan pass: tools_build_map_overwrite_test kills build_map child processes at
# points of a map rewrite; with an instrumented build_map it takes 170 s instead of 32 s, and the
# map builder's code is covered by unit_map_builder_test here.
SKIP=(tools_build_map_overwrite_test)

status=0
for s in $SANITIZERS; do
  case "$s" in
    asan) pass asan address,undefined unit_:test/unit ros_:test/ros tools_:test/tools || status=1 ;;
    tsan)
      # The threaded tests: every simulator test (the ray caster and the runs use a thread pool),
      # the chunk engine's worker threads, the map builder's parallel fit.
      pass tsan thread unit_:test/unit/sim unit_:test/unit/raster/chunk_engine_test.cpp \
        unit_:test/unit/mapping/map_builder_test.cpp || status=1
      ;;
    *) echo "[sanitizers] unknown pass '$s' (asan, tsan)" >&2; status=1 ;;
  esac
done
exit "$status"
