# Map tools: build_map (inputs: PCD map, KITTI-style scans, rosbag, synthetic street) and
# map_info (summary, CRC verification, top-down export). The PCL and rosbag readers live in the
# static library gmm_map_readers so other tools and nodes can reuse them; the KITTI reader is in
# the ROS-free core (core/kitti_source.h).
add_library(gmm_map_readers STATIC
  src/tools/build_map/build_map_options.cpp
  src/tools/build_map/build_map_pcd.cpp
  src/tools/build_map/build_map_rosbag.cpp
  src/tools/build_map/build_map_synthetic.cpp
  src/tools/common/progress_bar.cpp)
set_target_properties(gmm_map_readers PROPERTIES POSITION_INDEPENDENT_CODE ON)
target_include_directories(gmm_map_readers PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
target_include_directories(gmm_map_readers SYSTEM PUBLIC ${catkin_INCLUDE_DIRS} ${PCL_INCLUDE_DIRS})
target_compile_definitions(gmm_map_readers PUBLIC ${PCL_DEFINITIONS})
target_link_libraries(gmm_map_readers PUBLIC gmm_core ${catkin_LIBRARIES} ${PCL_LIBRARIES})

gmm_add_tool(build_map SOURCES src/tools/build_map/build_map.cpp LIBS gmm_map_readers)
gmm_add_tool(map_info SOURCES src/tools/map_info/map_info.cpp LIBS gmm_core)

if(CATKIN_ENABLE_TESTING)
  # Reader tests write a small PCD and a small bag (no ROS master needed).
  catkin_add_gtest(tools_build_map_readers_test test/tools/build_map/build_map_readers_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_build_map_readers_test gmm_map_readers gtest_main)
endif()
