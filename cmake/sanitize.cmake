# GMM_SANITIZE: a sanitizer build (scripts/run_sanitizers.sh makes one per sanitizer, each in its
# own build directory). Empty (the default): nothing changes. Otherwise a comma-separated
# -fsanitize= list, e.g. -DGMM_SANITIZE=address,undefined or -DGMM_SANITIZE=thread: every target
# of the project then compiles with -fsanitize=<list> -fno-omit-frame-pointer -O1 -g1 (the
# options come after the build type's -O3, so -O1 wins; -g1: line tables for the reports' stack
# traces) and links the sanitizer runtimes. With `undefined`, the first report aborts
# (-fno-sanitize-recover); the null and alignment checks are left out (below). gmm_core and
# gmm_sim drop -Werror there. Included before any target is defined.
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
    list(APPEND GMM_SANITIZE_FLAGS -fno-sanitize=null,alignment -fno-sanitize-recover=undefined)
  endif()
  add_compile_options(${GMM_SANITIZE_FLAGS})
  add_link_options(-fsanitize=${GMM_SANITIZE})
  message(STATUS "gmm_localization: sanitizer build (${GMM_SANITIZE_FLAGS})")
endif()
