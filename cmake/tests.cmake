# Tests in three tiers (DESIGN.md 4.6):
#  test/unit/*_test.cpp         gtest on the ROS-free core and simulator, no master
#  test/ros/*_test.cpp          gtest on conversions and ROS-side classes, no master
#  test/integration/*.test      rostests that run the real launch files
# Fragments under cmake/tests/ add their own targets.
file(GLOB GMM_TEST_FRAGMENTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/cmake/tests/*.cmake)
foreach(fragment ${GMM_TEST_FRAGMENTS})
  include(${fragment})
endforeach()

# gmm_release_tests: what the test command (scripts/run_tests.sh) builds in this (Release) build -
# everything of `tests` but the master-free gtests (unit_*, ros_*, tools_*_test) that the ASan
# pass compiles and runs (scripts/run_sanitizers.sh): the rostests' executables and fixture, and
# the gtests named in scripts/sanitizer_skip.txt. `make tests` still builds every test.
if(TARGET tests)
  file(STRINGS ${CMAKE_CURRENT_SOURCE_DIR}/scripts/sanitizer_skip.txt GMM_SANITIZER_SKIP
    REGEX "^[a-z]")
  get_property(GMM_ALL_TEST_TARGETS TARGET tests PROPERTY MANUALLY_ADDED_DEPENDENCIES)
  set(GMM_RELEASE_TEST_TARGETS)
  foreach(t ${GMM_ALL_TEST_TARGETS})
    if(NOT t MATCHES "^(unit|ros|tools)_.*_test$" OR t IN_LIST GMM_SANITIZER_SKIP)
      list(APPEND GMM_RELEASE_TEST_TARGETS ${t})
    else()
      # The ASan pass finds its tests by file name (<prefix><file name>): a target named
      # otherwise would run nowhere.
      get_target_property(test_sources ${t} SOURCES)
      list(GET test_sources 0 test_source)
      get_filename_component(test_file ${test_source} NAME_WE)
      string(REGEX MATCH "^(unit|ros|tools)_" test_prefix ${t})
      if(NOT t STREQUAL "${test_prefix}${test_file}")
        message(FATAL_ERROR "test target ${t} is built from ${test_file}: the ASan pass "
          "(scripts/run_sanitizers.sh) runs the master-free gtests by their file names; name "
          "the file or the target so that the target is ${test_prefix}<file name>")
      endif()
    endif()
  endforeach()
  foreach(t ${GMM_SANITIZER_SKIP})
    if(NOT TARGET ${t})
      message(FATAL_ERROR "scripts/sanitizer_skip.txt names ${t}, which is no test target")
    endif()
  endforeach()
  add_custom_target(gmm_release_tests)
  add_dependencies(gmm_release_tests ${GMM_RELEASE_TEST_TARGETS})
endif()
