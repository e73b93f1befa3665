# gtest on conversions and ROS-side classes (no master needed).
file(GLOB GMM_ROS_TESTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/*_test.cpp)
foreach(test_source ${GMM_ROS_TESTS})
  get_filename_component(test_name ${test_source} NAME_WE)
  catkin_add_gtest(ros_${test_name} ${test_source}
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(ros_${test_name} gmm_ros gtest_main)
endforeach()
