# Command-line tools (src/tools). gmm_add_tool(name source... LIBS libs...) builds one into the
# package's devel lib directory, so `rosrun gmm_localization <name>` finds it.
function(gmm_add_tool name)
  cmake_parse_arguments(T "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} ${T_LIBS})
  target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
  set_target_properties(${name} PROPERTIES
    RUNTIME_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_BIN_DESTINATION})
  install(TARGETS ${name} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()

# Each area lists its tools in its own file under cmake/tools/.
file(GLOB GMM_TOOL_FRAGMENTS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/cmake/tools/*.cmake)
foreach(fragment ${GMM_TOOL_FRAGMENTS})
  include(${fragment})
endforeach()

if(CATKIN_ENABLE_TESTING)
  # The conventions every tool follows (src/tools/common/cli_args.h): runs the built binaries.
  set(GMM_ALL_TOOLS build_map simulate evaluate bench_registration kitti_check map_info
    sim_validate)
  catkin_add_gtest(tools_cli_conventions_test test/tools/common/cli_conventions_test.cpp)
  target_include_directories(tools_cli_conventions_test PRIVATE
    ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
  target_link_libraries(tools_cli_conventions_test gtest_main)
  target_compile_definitions(tools_cli_conventions_test PRIVATE
    GMM_TOOLS_DIR="${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_BIN_DESTINATION}")
  add_dependencies(tools_cli_conventions_test ${GMM_ALL_TOOLS})
endif()
