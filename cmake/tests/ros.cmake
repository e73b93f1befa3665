# gtest on conversions and ROS-side classes (no master needed).
file(GLOB GMM_ROS_TESTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/*_test.cpp)
foreach(test_source ${GMM_ROS_TESTS})
  get_filename_component(test_name ${test_source} NAME_WE)
  catkin_add_gtest(ros_${test_name} ${test_source}
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(ros_${test_name} gmm_ros gtest_main)
endforeach()

# The unknown-key checks read the shipped config/*.yaml through the evaluate tool's YAML reader.
if(TARGET ros_params_unknown_keys_test)
  target_link_libraries(ros_params_unknown_keys_test gmm_evaluate)
  target_compile_definitions(ros_params_unknown_keys_test PRIVATE
    GMM_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config")
endif()
