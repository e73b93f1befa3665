# rostest of the matcher and ekf nodelets (test/integration/matcher_ekf_nodelets.test): both
# nodelets in one manager, driven on sim time by a gtest node that publishes a synthetic map,
# INS, IMU and scans (test/integration/matcher_ekf_nodelets_test.cpp).
find_package(rostest REQUIRED)

add_rostest_gtest(rostest_matcher_ekf_nodelets test/integration/matcher_ekf_nodelets.test
  test/integration/matcher_ekf_nodelets_test.cpp)
target_link_libraries(rostest_matcher_ekf_nodelets gmm_ros)
add_dependencies(rostest_matcher_ekf_nodelets gmm_matcher_nodelet gmm_ekf_nodelet)
