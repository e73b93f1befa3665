# gmm_sim: the ROS-free simulator (procedural town, HDL-32E ray casting on Embree 3, vehicle
# and INS models). Same rules as gmm_core: no ROS, no PCL, and -Werror on its sources.
file(GLOB GMM_SIM_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/sim/*.cpp)
add_library(gmm_sim SHARED ${GMM_SIM_SOURCES})
target_include_directories(gmm_sim PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_link_libraries(gmm_sim PUBLIC gmm_core embree Eigen3::Eigen Threads::Threads)
target_link_options(gmm_sim PRIVATE -Wl,--no-undefined)
if(NOT GMM_SANITIZE)  # sanitizer builds (-O1, instrumented) can warn spuriously: no -Werror
  target_compile_options(gmm_sim PRIVATE -Werror)
endif()
set_target_properties(gmm_sim PROPERTIES
  LIBRARY_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_LIB_DESTINATION})
install(TARGETS gmm_sim LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
