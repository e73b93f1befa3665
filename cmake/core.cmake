# gmm_core: the ROS-free core. It gets Eigen, zlib, threads and GeographicLib (the map's
# georeference, core/map/georeference.h) only; the target links with
# --no-undefined, so any use of a ROS or PCL symbol fails to link, and scripts/check_core_deps.sh
# (run by the test command) rejects ROS/PCL includes under core/ and sim/. Its own sources build
# with -Werror on top of the project's -Wall -Wextra -Wno-unused-parameter: a warning in the core
# fails the build (headers included by other targets are not affected there).
file(GLOB_RECURSE GMM_CORE_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/core/*.cpp)
add_library(gmm_core SHARED ${GMM_CORE_SOURCES})
target_include_directories(gmm_core PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_include_directories(gmm_core SYSTEM PRIVATE ${GeographicLib_INCLUDE_DIRS})
target_link_libraries(gmm_core PUBLIC Eigen3::Eigen ZLIB::ZLIB Threads::Threads)
target_link_libraries(gmm_core PRIVATE ${GeographicLib_LIBRARIES})
target_link_options(gmm_core PRIVATE -Wl,--no-undefined)
# Calls inside the core bind to the core's own functions: no PLT hop per call in the matching
# loops (a point's cell values, the kernel), and GCC may inline them (nobody interposes them).
target_compile_options(gmm_core PRIVATE -fno-semantic-interposition)
target_link_options(gmm_core PRIVATE -Wl,-Bsymbolic-functions)
if(NOT GMM_SANITIZE)  # sanitizer builds (-O1, instrumented) can warn spuriously: no -Werror
  target_compile_options(gmm_core PRIVATE -Werror)
endif()
set_target_properties(gmm_core PROPERTIES
  LIBRARY_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_LIB_DESTINATION})
install(TARGETS gmm_core LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
