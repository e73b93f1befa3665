# Tests in three tiers (DESIGN.md 4.6):
#  test/unit/*_test.cpp         gtest on the ROS-free core and simulator, no master
#  test/ros/*_test.cpp          gtest on conversions and ROS-side classes, no master
#  test/integration/*.test      rostests that run the real launch files
# Fragments under cmake/tests/ add their own targets.
file(GLOB GMM_TEST_FRAGMENTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/cmake/tests/*.cmake)
foreach(fragment ${GMM_TEST_FRAGMENTS})
  include(${fragment})
endforeach()
