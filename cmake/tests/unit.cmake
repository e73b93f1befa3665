# One gtest binary per test file under test/unit (core and simulator, no ROS master).
# sim_*_test.cpp link the simulator too; the others only the core.
file(GLOB_RECURSE GMM_UNIT_TESTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/unit/*_test.cpp)
foreach(test_source ${GMM_UNIT_TESTS})
  get_filename_component(test_name ${test_source} NAME_WE)
  catkin_add_gtest(unit_${test_name} ${test_source}
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(unit_${test_name} gmm_core gtest_main)
  if(test_name MATCHES "^sim_")
    target_link_libraries(unit_${test_name} gmm_sim)
  endif()
  target_include_directories(unit_${test_name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/test/unit)
  target_compile_definitions(unit_${test_name} PRIVATE
    GMM_SHARED_DATA_DIR="${GMM_SHARED_DATA_DIR}")
endforeach()
