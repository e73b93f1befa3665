# bench_registration: the registration benchmark, with PCL NDT and GICP as peers. Its data
# readers (KITTI-style folders as build_map reads them), match methods, peers, options and
# per-run output are the static library gmm_bench, shared with kitti_check.
add_library(gmm_bench STATIC
  src/tools/bench/bench_data.cpp
  src/tools/bench/bench_global_miss.cpp
  src/tools/bench/bench_methods.cpp
  src/tools/bench/bench_options.cpp
  src/tools/bench/bench_output.cpp
  src/tools/bench/bench_peers.cpp)
target_include_directories(gmm_bench PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
target_include_directories(gmm_bench SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
target_compile_definitions(gmm_bench PRIVATE ${PCL_DEFINITIONS})
target_link_libraries(gmm_bench PUBLIC gmm_core ${PCL_LIBRARIES})

gmm_add_tool(bench_registration SOURCES src/tools/bench/bench_registration.cpp LIBS gmm_bench)

if(CATKIN_ENABLE_TESTING)
  # The data reader on generated KITTI-layout folders (layouts, skipped poses, calibration,
  # peer targets); bench_registration run on a KITTI-layout folder made from the real keyframes
  # (skipped when ../shared/data/real is absent), its map built by build_map --kitti-calib.
  catkin_add_gtest(tools_bench_data_test test/tools/bench/bench_data_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_bench_data_test gmm_bench gtest_main)
  catkin_add_gtest(tools_bench_registration_test test/tools/bench/bench_registration_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_bench_registration_test gmm_bench gtest_main)
  target_compile_definitions(tools_bench_registration_test PRIVATE
    GMM_SHARED_DATA_DIR="${GMM_SHARED_DATA_DIR}"
    GMM_BUILD_MAP_BINARY="$<TARGET_FILE:build_map>"
    GMM_BENCH_BINARY="$<TARGET_FILE:bench_registration>")
  add_dependencies(tools_bench_registration_test build_map bench_registration)
  # --methods on a generated painted street: every method's rows, a missing reflectivity layer
  # and scans without intensity refused.
  catkin_add_gtest(tools_bench_methods_test test/tools/bench/bench_methods_test.cpp
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(tools_bench_methods_test gmm_bench gtest_main)
  target_compile_definitions(tools_bench_methods_test PRIVATE
    GMM_BUILD_MAP_BINARY="$<TARGET_FILE:build_map>"
    GMM_BENCH_BINARY="$<TARGET_FILE:bench_registration>")
  add_dependencies(tools_bench_methods_test build_map bench_registration)
endif()
