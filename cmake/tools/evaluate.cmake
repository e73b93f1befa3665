# evaluate: the paper's experiments on a localization bag (LocalizerPipeline offline,
# options from the same YAML files as the nodelets, parsed with yaml-cpp) or on the recording of
# a real replay. The library gmm_evaluate holds everything but main() so the tests can use it.
find_package(yaml-cpp REQUIRED)

add_library(gmm_evaluate STATIC
  src/tools/evaluate/evaluate_bag.cpp
  src/tools/evaluate/evaluate_gnss.cpp
  src/tools/evaluate/evaluate_integrity.cpp
  src/tools/evaluate/evaluate_localize.cpp
  src/tools/evaluate/evaluate_map.cpp
  src/tools/evaluate/evaluate_map_frame.cpp
  src/tools/evaluate/evaluate_metrics.cpp
  src/tools/evaluate/evaluate_offsets.cpp
  src/tools/evaluate/evaluate_options.cpp
  src/tools/evaluate/evaluate_recorded.cpp
  src/tools/evaluate/evaluate_report.cpp
  src/tools/evaluate/evaluate_summary.cpp
  src/tools/evaluate/evaluate_yaml.cpp
  src/tools/common/progress_bar.cpp)
target_include_directories(gmm_evaluate PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
target_link_libraries(gmm_evaluate PUBLIC gmm_ros yaml-cpp Threads::Threads)
# The package's config/ directory is the default for --config-dir.
target_compile_definitions(gmm_evaluate PRIVATE
  GMM_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config")

gmm_add_tool(evaluate SOURCES src/tools/evaluate/evaluate.cpp LIBS gmm_evaluate)
target_compile_definitions(evaluate PRIVATE GMM_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config")

if(CATKIN_ENABLE_TESTING)
  # The evaluation maths, the YAML parameter source, the bag reader and the recorded-replay
  # reader (no master; the bag tests write temporary bags).
  foreach(test_name evaluate_metrics_test evaluate_params_test evaluate_bag_test
      evaluate_map_frame_test evaluate_recorded_test)
    catkin_add_gtest(tools_${test_name} test/tools/evaluate/${test_name}.cpp
      WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
    target_link_libraries(tools_${test_name} gmm_evaluate gtest_main)
    target_compile_definitions(tools_${test_name} PRIVATE
      GMM_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/config")
  endforeach()
endif()
