# kitti_check: real-data checks on KITTI keyframes (docs/real_data.md): mixtures per class of
# cell, and leave-one-out registration against PCL NDT and GICP. The peers and the KITTI-style
# data reader are the benchmark's own (gmm_bench, cmake/tools/bench.cmake), the integrity summary
# evaluate's (gmm_evaluate).
add_library(gmm_kitti_check STATIC
  src/tools/kitti_check/kitti_check_data.cpp
  src/tools/kitti_check/kitti_check_register.cpp
  src/tools/kitti_check/kitti_check_report.cpp
  src/tools/kitti_check/kitti_check_cells.cpp
  src/tools/kitti_check/kitti_check_cells_report.cpp)
target_include_directories(gmm_kitti_check PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
target_include_directories(gmm_kitti_check SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
target_compile_definitions(gmm_kitti_check PRIVATE ${PCL_DEFINITIONS})
target_link_libraries(gmm_kitti_check PUBLIC gmm_bench gmm_evaluate gmm_core ${PCL_LIBRARIES})

gmm_add_tool(kitti_check SOURCES src/tools/kitti_check/kitti_check.cpp LIBS gmm_kitti_check)

if(CATKIN_ENABLE_TESTING)
  # The classifier on a synthetic scene; leave-one-out on the real keyframes (skipped when
  # ../shared/data/real is absent); the record layouts of the data reader.
  foreach(t kitti_check_cells_test kitti_check_register_test kitti_check_data_test)
    catkin_add_gtest(tools_${t} test/tools/kitti_check/${t}.cpp WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
    target_link_libraries(tools_${t} gmm_kitti_check gtest_main)
    target_compile_definitions(tools_${t} PRIVATE GMM_SHARED_DATA_DIR="${GMM_SHARED_DATA_DIR}")
  endforeach()
endif()
