# gmm_ros: conversions between ROS messages and core types, parameter loading, and the classes
# the nodelets build. gmm_localization_nodelets: the nodelet entry points (src/nodelets).
file(GLOB GMM_ROS_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/ros/*.cpp)
add_library(gmm_ros SHARED ${GMM_ROS_SOURCES})
# The generated message headers (devel include/) come from generate_messages(), which adds them
# to the directory's include path.
target_include_directories(gmm_ros PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
# PUBLIC: the targets built on gmm_ros compile its headers, which include ROS and PCL ones.
# None is exported (no install(EXPORT)), so no absolute path leaves the build.
#catkin_lint: ignore_once external_interface_path
target_include_directories(gmm_ros SYSTEM PUBLIC ${catkin_INCLUDE_DIRS} ${PCL_INCLUDE_DIRS})
target_compile_definitions(gmm_ros PUBLIC ${PCL_DEFINITIONS})
target_link_libraries(gmm_ros PUBLIC gmm_core gmm_sim ${catkin_LIBRARIES} ${PCL_LIBRARIES})
add_dependencies(gmm_ros ${PROJECT_NAME}_generate_messages_cpp)
set_target_properties(gmm_ros PROPERTIES
  LIBRARY_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_LIB_DESTINATION})

# One library per nodelet (src/nodelets/<name>_nodelet.cpp -> libgmm_<name>_nodelet), each
# listed in nodelet_plugins.xml: a nodelet's entry point is a few lines building its class.
file(GLOB GMM_NODELET_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/nodelets/*_nodelet.cpp)
install(TARGETS gmm_ros LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
foreach(source ${GMM_NODELET_SOURCES})
  get_filename_component(name ${source} NAME_WE)
  add_library(gmm_${name} SHARED ${source})
  target_link_libraries(gmm_${name} PUBLIC gmm_ros)
  set_target_properties(gmm_${name} PROPERTIES
    LIBRARY_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_LIB_DESTINATION})
  install(TARGETS gmm_${name} LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
endforeach()
