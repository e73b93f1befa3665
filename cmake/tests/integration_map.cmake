# rostests of the map server and the cloud merger (test/integration). Each launch file starts a
# nodelet manager; the test node (gtest) drives the nodelet through its topics and services.
find_package(rostest REQUIRED)
find_package(roslaunch REQUIRED)

add_rostest_gtest(rostest_map_server test/integration/map_server.test
  test/integration/map_server_test_node.cpp)
target_link_libraries(rostest_map_server gmm_ros)
target_include_directories(rostest_map_server PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/test/unit)
add_dependencies(rostest_map_server gmm_map_server_nodelet)

add_rostest_gtest(rostest_cloud_merger test/integration/cloud_merger.test
  test/integration/cloud_merger_test_node.cpp)
target_link_libraries(rostest_cloud_merger gmm_ros)
add_dependencies(rostest_cloud_merger gmm_cloud_merger_nodelet)

# The standalone map server launch file: syntax, packages and nodes it names.
roslaunch_add_file_check(launch/map_server.launch map:=/tmp/no_map)
