# Map tools: build_map (inputs: PCD map, KITTI-style scans, rosbag, synthetic street) and
# map_info (summary, CRC verification, top-down export). The PCD reader (our own, no PCL) and the
# rosbag reader live in the static library gmm_map_readers so other tools and nodes can reuse
# them; the KITTI reader is in the ROS-free core (core/mapping/kitti_source.h).
add_library(gmm_map_readers STATIC
  src/tools/build_map/build_map_georeference.cpp
  src/tools/build_map/build_map_help.cpp
  src/tools/build_map/build_map_layer_args.cpp
  src/tools/build_map/build_map_options.cpp
  src/tools/build_map/build_map_pcd.cpp
  src/tools/build_map/build_map_rosbag.cpp
  src/tools/build_map/build_map_synthetic.cpp
  src/tools/build_map/lzf.cpp
  src/tools/build_map/pcd_header.cpp
  src/tools/build_map/pcd_reader.cpp
  src/tools/common/progress_bar.cpp)
set_target_properties(gmm_map_readers PROPERTIES POSITION_INDEPENDENT_CODE ON)
# In a unity build (CI, the sanitizer builds) these two compile alone: their private structs
# hold types of their own anonymous namespace, which GCC reports (-Wsubobject-linkage) once the
# source is included into a batch.
set_source_files_properties(src/tools/build_map/build_map_rosbag.cpp
  src/tools/build_map/build_map_synthetic.cpp PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
target_include_directories(gmm_map_readers PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
target_include_directories(gmm_map_readers SYSTEM PUBLIC ${catkin_INCLUDE_DIRS})
# gmm_ros: the rosbag reader reads clouds with the matcher's reader (ros/cloud_conversion.h).
target_link_libraries(gmm_map_readers PUBLIC gmm_core gmm_ros ${catkin_LIBRARIES})

gmm_add_tool(build_map SOURCES src/tools/build_map/build_map.cpp LIBS gmm_map_readers)
gmm_add_tool(map_info SOURCES src/tools/map_info/map_info.cpp LIBS gmm_core)

if(CATKIN_ENABLE_TESTING)
  # build_map's georeference options (--utm-zone, --epsg, --mgrs-origin, --georef-origin).
  catkin_add_gtest(tools_build_map_georeference_test
    test/tools/build_map/build_map_georeference_test.cpp)
  target_link_libraries(tools_build_map_georeference_test gmm_map_readers gtest_main)
  # Reader tests write a small bag (no ROS master needed).
  catkin_add_gtest(tools_build_map_readers_test test/tools/build_map/build_map_readers_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_build_map_readers_test gmm_map_readers gtest_main)
  # build_map --bag end to end: Ouster clouds, a /tf_static chain, poses from /tf.
  catkin_add_gtest(tools_build_map_bag_test test/tools/build_map/build_map_bag_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_build_map_bag_test gmm_map_readers gtest_main)
  target_compile_definitions(tools_build_map_bag_test PRIVATE
    GMM_BUILD_MAP_BINARY="$<TARGET_FILE:build_map>")
  add_dependencies(tools_build_map_bag_test build_map)
  # build_map --overwrite killed with SIGKILL in both passes and in the swap, and run out of
  # space on a small tmpfs (skipped where mounting is not permitted): the old map survives.
  catkin_add_gtest(tools_build_map_overwrite_test test/tools/build_map/build_map_overwrite_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_build_map_overwrite_test gmm_core gtest_main)
  target_compile_definitions(tools_build_map_overwrite_test PRIVATE
    GMM_BUILD_MAP_BINARY="$<TARGET_FILE:build_map>" GMM_MAP_INFO_BINARY="$<TARGET_FILE:map_info>")
  add_dependencies(tools_build_map_overwrite_test build_map map_info)
  # build_map --layer reflectivity: the readers' intensities and vehicle origins, the command
  # line's refusals, and build_map + map_info on a tiny KITTI directory of a painted road.
  catkin_add_gtest(tools_build_map_layer_test test/tools/build_map/build_map_layer_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_build_map_layer_test gmm_map_readers gtest_main)
  target_compile_definitions(tools_build_map_layer_test PRIVATE
    GMM_BUILD_MAP_BINARY="$<TARGET_FILE:build_map>" GMM_MAP_INFO_BINARY="$<TARGET_FILE:map_info>")
  add_dependencies(tools_build_map_layer_test build_map map_info)
  # The PCD reader against malformed, double-precision, tiled and junk-laden files; PCL only
  # writes fixtures (its binary_compressed writer and LZF compressor).
  catkin_add_gtest(tools_build_map_pcd_test test/tools/build_map/build_map_pcd_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_include_directories(tools_build_map_pcd_test SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
  target_compile_definitions(tools_build_map_pcd_test PRIVATE ${PCL_DEFINITIONS})
  target_link_libraries(tools_build_map_pcd_test gmm_map_readers gtest_main ${PCL_LIBRARIES})
endif()
