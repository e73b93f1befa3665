#!/usr/bin/env bash
# The fuzz pass of the test command (scripts/run_tests.sh calls it after the sanitizer pass):
# libFuzzer targets for every parser of outside input (test/fuzz/fuzz_<name>.cpp, what each
# covers: docs/fuzzing.md), built with clang-14 -fsanitize=fuzzer,address,undefined
# (-fno-sanitize-recover=undefined) in $GMM_WS/fuzz (the CMake project test/fuzz/CMakeLists.txt).
# Steps:
#   1. build the targets and the seed writer (incremental after the first run);
#   2. write the seed corpora with the project's own writers (fuzz_make_seeds, into
#      $GMM_WS/fuzz_runs/seeds; nothing binary is stored in the repository for them);
#   3. replay every reproducer under test/fuzz/regressions/<target>/ (each must now pass);
#   4. run each target for GMM_FUZZ_TIME seconds (20 by default; 0: steps 1-3 only) on its
#      corpus ($GMM_WS/fuzz_runs/corpus/<target>, kept between runs, so coverage accumulates;
#      GMM_FUZZ_FRESH=1 starts it afresh) plus the seeds, GMM_JOBS targets at a time.
# Any crash, sanitizer report, failed contract check (FUZZ_CHECK), leak, timeout (a unit
# longer than GMM_FUZZ_TIMEOUT s, 10 by default) or out-of-memory (over 2048 MB) fails the
# pass; the input is written to $GMM_WS/fuzz_runs/artifacts/<target>/ and the report printed
# (logs: $GMM_WS/fuzz_runs/logs/<target>.log). A reproducer of a bug belongs in
# test/fuzz/regressions/<target>/ (docs/fuzzing.md), so that this pass replays it every run.
# GMM_FUZZ_TARGETS selects targets (names without fuzz_, space-separated; default: all);
# GMM_FUZZ_CXX the compiler (clang++-14); GMM_BUILD_ONLY=1 stops after step 1 (see
# run_sanitizers.sh); GMM_BUILD_LOCK a lock file that the build step (only)
# holds with flock, for machines where builds are serialised. Exit status non-zero when the
# build, the seeds, a regression or a fuzz run fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
# shellcheck source=job_pool.sh
source "$(dirname "${BASH_SOURCE[0]}")/job_pool.sh"
FUZZ_TIME="${GMM_FUZZ_TIME:-20}"
TIMEOUT="${GMM_FUZZ_TIMEOUT:-10}"
JOBS="${GMM_JOBS:-$(nproc)}"
CXX="${GMM_FUZZ_CXX:-clang++-14}"
BUILD="$GMM_WS/fuzz"
RUNS="$GMM_WS/fuzz_runs"
REGRESSIONS="$GMM_REPO/test/fuzz/regressions"
start=$SECONDS

# --- 1. build ---
cxx="$(command -v "$CXX")" ||
  { echo "[fuzz] no compiler $CXX (libFuzzer needs Clang)" >&2; exit 1; }
cc="$(command -v "$(sed 's/clang++/clang/' <<<"$(basename "$cxx")")")" ||
  { echo "[fuzz] no C compiler next to $cxx" >&2; exit 1; }
build() {
  if [ -n "${GMM_BUILD_LOCK:-}" ]; then flock "$GMM_BUILD_LOCK" "$@"; else "$@"; fi
}
if [ ! -f "$BUILD/build.ninja" ] ||
  ! grep -qx "CMAKE_CXX_COMPILER:[A-Z]*=$cxx" "$BUILD/CMakeCache.txt"; then
  rm -rf "$BUILD"
fi
mkdir -p "$BUILD"
if [ ! -f "$BUILD/build.ninja" ]; then
  cmake -S "$GMM_REPO/test/fuzz" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_C_COMPILER="$cc" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 >"$BUILD/cmake.log" 2>&1 ||
    { cat "$BUILD/cmake.log"; echo "[fuzz] configure failed" >&2; exit 1; }
fi
build ninja -C "$BUILD" -j"$JOBS" >"$BUILD/build.log" 2>&1 ||
  { tail -n 80 "$BUILD/build.log"; echo "[fuzz] build failed" >&2; exit 1; }
built=$SECONDS
if [ "${GMM_BUILD_ONLY:-0}" = 1 ]; then
  echo "[fuzz] built in $((built - start)) s (GMM_BUILD_ONLY: not run)"
  exit 0
fi

mapfile -t all < <(find "$GMM_REPO/test/fuzz" -maxdepth 1 -name 'fuzz_*.cpp' -printf '%f\n' |
  sed 's/^fuzz_//; s/\.cpp$//' | sort)
if [ -n "${GMM_FUZZ_TARGETS:-}" ]; then
  read -r -a targets <<<"$GMM_FUZZ_TARGETS"
else
  targets=("${all[@]}")
fi
for t in "${targets[@]}"; do
  [ -x "$BUILD/fuzz_$t" ] || { echo "[fuzz] no target fuzz_$t (have: ${all[*]})" >&2; exit 1; }
done

# --- 2. seeds ---
rm -rf "$RUNS/seeds" "$RUNS/tmp"
mkdir -p "$RUNS/logs" "$RUNS/tmp"
[ "${GMM_FUZZ_FRESH:-0}" = 1 ] && rm -rf "$RUNS/corpus"
"$BUILD/fuzz_make_seeds" "$RUNS/seeds" "$GMM_REPO/config" >"$RUNS/logs/make_seeds.log" 2>&1 ||
  { cat "$RUNS/logs/make_seeds.log"; echo "[fuzz] the seed writer failed" >&2; exit 1; }
echo "[fuzz] built in $((built - start)) s; $(tail -n 1 "$RUNS/logs/make_seeds.log")"

# Reports: every sanitizer report and leak fails (halt_on_error; UBSan aborts); libFuzzer's own
# -detect_leaks is on. The KITTI target's scan directory goes under $RUNS/tmp.
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:abort_on_error=0:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:print_summary=1"
export TMPDIR="$RUNS/tmp"
FLAGS=(-timeout="$TIMEOUT" -rss_limit_mb=2048 -print_final_stats=1)

REPORT_LINES="ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error|FUZZ_CHECK|SUMMARY"
REPORT_LINES+="|Test unit written|ALARM|out-of-memory|terminate called|what\(\)"
report() {  # report <log>: the lines that say what failed
  grep -nE "$REPORT_LINES" "$1" | head -n 20 || true
}

# --- 3. regressions ---
status=0
replayed=0
for dir in "$REGRESSIONS"/*/; do
  [ -d "$dir" ] || continue
  t="$(basename "$dir")"
  [ -x "$BUILD/fuzz_$t" ] || { echo "[fuzz] $dir: no target fuzz_$t" >&2; status=1; continue; }
  for input in "$dir"*; do
    [ -f "$input" ] || continue
    replayed=$((replayed + 1))
    log="$RUNS/logs/regression_${t}_$(basename "$input").log"
    if (cd "$RUNS" && "$BUILD/fuzz_$t" "${FLAGS[@]}" "$input") >"$log" 2>&1; then
      echo "[fuzz] regression OK     $t/$(basename "$input")"
    else
      echo "[fuzz] regression FAILED $t/$(basename "$input") ($log):"
      report "$log"
      status=1
    fi
  done
done
[ "$replayed" -gt 0 ] || echo "[fuzz] no regression inputs under $REGRESSIONS"

# --- 4. bounded fuzzing ---
run_one() {  # run_one <target>: fuzzes for FUZZ_TIME s; prints one summary line
  local t="$1" log="$RUNS/logs/$1.log"
  mkdir -p "$RUNS/corpus/$t" "$RUNS/artifacts/$t"
  local rc=0
  (cd "$RUNS" && "$BUILD/fuzz_$t" "${FLAGS[@]}" -max_total_time="$FUZZ_TIME" \
    -artifact_prefix="$RUNS/artifacts/$t/" "$RUNS/corpus/$t" "$RUNS/seeds/$t") >"$log" 2>&1 ||
    rc=$?
  local execs rate cov
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)"
  cov="$(grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+/[0-9]+[a-zA-Z]*' "$log" | tail -n 1 || true)"
  if [ "$rc" -eq 0 ]; then
    echo "[fuzz] OK     $t: ${execs:-?} execs (${rate:-?}/s), ${cov:-no coverage line}"
  else
    echo "[fuzz] FAILED $t (exit $rc, $log): ${execs:-?} execs, ${cov:-no coverage line}"
    report "$log"
    return 1
  fi
}

if [ "$FUZZ_TIME" -gt 0 ]; then
  fuzz_start=$SECONDS
  failed=0
  run_pool "$JOBS" run_one "${targets[@]}" || failed=$?
  echo "[fuzz] ${#targets[@]} targets x ${FUZZ_TIME} s in $((SECONDS - fuzz_start)) s," \
    "$((${#targets[@]} - failed))/${#targets[@]} without a finding"
  [ "$failed" -eq 0 ] || status=1
fi
echo "[fuzz] total $((SECONDS - start)) s"
exit "$status"
