# GMM_SANITIZE: a sanitizer build (scripts/run_sanitizers.sh makes one per sanitizer, each in its
# own build directory). Empty (the default): nothing changes. Otherwise a comma-separated
# -fsanitize= list, e.g. -DGMM_SANITIZE=address,undefined or -DGMM_SANITIZE=thread: every target
# of the project then compiles with -fsanitize=<list> -fno-omit-frame-pointer -O1 -g1 (the
# options come after the build type's -O3, so -O1 wins; -g1: line tables for the reports' stack
# traces) and links the sanitizer runtimes. With `undefined`, the first report aborts
# (-fno-sanitize-recover); the null, alignment, object-size and pointer-overflow checks are
# left out (below). gmm_core and gmm_sim drop -Werror there. Included before any target is
# defined.
# (catkin_lint would have the project's name in a global variable: GMM_SANITIZE is the option's
# name that scripts/run_sanitizers.sh and the docs use.)
#catkin_lint: ignore_once global_var_collision
set(GMM_SANITIZE "" CACHE STRING
  "-fsanitize= list for a sanitizer build (address,undefined or thread); empty: none")
if(GMM_SANITIZE)
  if(GMM_SANITIZE MATCHES "thread" AND GMM_SANITIZE MATCHES "address")
    message(FATAL_ERROR "GMM_SANITIZE=${GMM_SANITIZE}: thread and address do not combine")
  endif()
  set(GMM_SANITIZE_FLAGS -fsanitize=${GMM_SANITIZE} -fno-omit-frame-pointer -O1 -g1)
  if(GMM_SANITIZE MATCHES "undefined")
    # Without the null and alignment checks: they instrument every member access and double
    # the compile time of the Eigen-heavy sources (measured with GCC 12: 8 s instead of 15 s for
    # a test file, about ASan's own cost). A null dereference still fails under ASan (SEGV with
    # its stack); misaligned loads are not reported.
    # Nor object-size and pointer-overflow: they check every Eigen index computation and make
    # up nearly all of UBSan's compile time on the Eigen-heavy sources (Clang 14, CPU s, ASan
    # alone / ASan+UBSan / ASan+UBSan without the two: ekf_simulation_test.cpp 10.5 / 15.0 /
    # 9.0, ekf_update.cpp 8.2 / 13.4 / 8.5). An access beyond an object is ASan's own check
    # (redzones); a wrapped pointer that is dereferenced fails there too, one never dereferenced
    # goes unreported.
    list(APPEND GMM_SANITIZE_FLAGS -fno-sanitize=null,alignment,object-size,pointer-overflow
      -fno-sanitize-recover=undefined)
  endif()
  add_compile_options(${GMM_SANITIZE_FLAGS})
  add_link_options(-fsanitize=${GMM_SANITIZE})
  # RPATH, not RUNPATH: the test binaries load the instrumented libraries of their own build
  # directory even when LD_LIBRARY_PATH names the main build's (a sourced devel/setup.bash does;
  # RUNPATH comes after LD_LIBRARY_PATH). Libraries built from other headers than the test's
  # (the main build's, of an older tree) gave ASan stack-buffer-overflows in the options tests.
  add_link_options(-Wl,--disable-new-dtags)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    # Clang links its runtime statically into executables only; the shared libraries (linked
    # with --no-undefined) need the shared runtime, as GCC uses by default, found by RPATH.
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} --print-resource-dir
      OUTPUT_VARIABLE GMM_CLANG_RESOURCE_DIR OUTPUT_STRIP_TRAILING_WHITESPACE)
    add_link_options(-shared-libsan -Wl,-rpath,${GMM_CLANG_RESOURCE_DIR}/lib/linux)
  endif()
  # Unity builds (sources of a library compiled in batches of 8): the instrumented build parses
  # the ROS, PCL and Eigen headers once per batch instead of once per source, about half its
  # compile time (the sanitizer pass is the largest part of the test command). Test executables
  # have one source each and are unaffected. The main build stays one source at a time.
  set(CMAKE_UNITY_BUILD ON)
  message(STATUS "${PROJECT_NAME}: sanitizer build (${GMM_SANITIZE_FLAGS}, unity)")
endif()
