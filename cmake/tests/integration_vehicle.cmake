# Rostests of the real launch files on a fixture generated at build time:
# scripts/make_test_fixture.sh runs the repository's simulate and build_map (a 250 m town, a
# 20 s drive, its map; about 15-20 s on 2 cores) into the build directory.
#  - roslaunch checks of every launch file (with their required args);
#  - vehicle_nodelets:   localization.launch with all four nodelets in one manager, wired;
#  - vehicle_replay:     replay.launch plays the drive; the EKF ends within 0.3 m and 1 deg of
#                        the truth, statuses per scan, odometry at its rate;
#  - vehicle_stale_start: the same launch with the bag played from 3 s in (the initial pose ~20 m
#                        stale): nothing wrong accepted, relocalized by the global search;
#  - vehicle_robustness: localization.launch under missing TF, IMU and INS dropouts, a vehicle
#                        off the map (the test node plays the drive with those faults);
#  - vehicle_kidnap:     localization.launch while the test node jumps the vehicle 50 m and
#                        90 deg: detected, relocalized by the global search, nothing wrong
#                        reported as good;
#  - vehicle_bad_input:  localization.launch against the bad-input matrix (bad clouds, stamps,
#                        NaN inputs, a rogue map index, broken map directories) while it drives;
#  - vehicle_gnss_start: localization.launch gnss_initializer:=true started from GNSS fixes;
#  - vehicle_global_start: replay.launch with no pose at all (the global start runs by default):
#                        the global window swept over the map finds the vehicle;
#  - vehicle_external_filter: localization.launch ekf:=false prior_topic:=/odometry/filtered with
#                        a stand-in for robot_localization (wiring, TF, config/robot_localization
#                        .yaml), and vehicle_ekf_no_tf (same binary): ekf_publish_tf:=false;
#  - vehicle_ins_adapter: localization.launch ins_adapter:=true ins_driver:=autoware_lvx on a
#                        drive shaped like that driver's output;
#  - vehicle_fused:      replay.launch method:=fused (two map servers, both layers matched) on
#                        the first 8 s of the drive; vehicle_fused_waiting: the matcher's
#                        answers without a usable reflectivity layer.
find_package(rostest REQUIRED)
find_package(roslaunch REQUIRED)

roslaunch_add_file_check(launch/localization.launch map:=/tmp/no_map)
roslaunch_add_file_check(launch/localization.launch map:=/tmp/no_map merge_clouds:=true rviz:=true
  use_initial_pose:=true diagnostics_aggregator:=true)
roslaunch_add_file_check(launch/localization.launch map:=/tmp/no_map ins_adapter:=true
  ins_driver:=clearpath_applanix_bridge ekf_publish_tf:=false)
roslaunch_add_file_check(launch/localization.launch map:=/tmp/no_map ekf:=false
  prior_topic:=/odometry/filtered gnss_initializer:=true gnss_heading_topic:=/gnss/heading)
roslaunch_add_file_check(launch/replay.launch map:=/tmp/no_map bag:=/tmp/no.bag)
roslaunch_add_file_check(launch/localization.launch map:=/tmp/no_map global_start:=true)
roslaunch_add_file_check(launch/localization.launch map:=/tmp/no_map method:=fused
  use_initial_pose:=true)
roslaunch_add_file_check(launch/replay.launch map:=/tmp/no_map bag:=/tmp/no.bag
  record:=/tmp/out.bag rviz:=true merge_clouds:=true)

set(GMM_VEHICLE_FIXTURE ${CMAKE_CURRENT_BINARY_DIR}/test_fixture/vehicle)
add_custom_command(
  OUTPUT ${GMM_VEHICLE_FIXTURE}/fixture.launch ${GMM_VEHICLE_FIXTURE}/fixture.yaml
  COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/scripts/make_test_fixture.sh ${GMM_VEHICLE_FIXTURE}
          $<TARGET_FILE:simulate> $<TARGET_FILE:build_map>
  DEPENDS simulate build_map ${CMAKE_CURRENT_SOURCE_DIR}/scripts/make_test_fixture.sh
  COMMENT "Generating the vehicle rostest fixture (simulate + build_map)"
  VERBATIM)
add_custom_target(gmm_vehicle_fixture
  DEPENDS ${GMM_VEHICLE_FIXTURE}/fixture.launch ${GMM_VEHICLE_FIXTURE}/fixture.yaml)
if(TARGET tests)
  add_dependencies(tests gmm_vehicle_fixture)
endif()

set(GMM_VEHICLE_NODELETS gmm_map_server_nodelet gmm_matcher_nodelet gmm_ekf_nodelet
  gmm_cloud_merger_nodelet gmm_gnss_initializer_nodelet gmm_ins_adapter_nodelet
  gmm_global_start_nodelet)
foreach(name nodelets replay stale_start robustness kidnap bad_input gnss_start global_start
    external_filter ins_adapter fused fused_waiting)
  add_executable(rostest_vehicle_${name} EXCLUDE_FROM_ALL
    test/integration/vehicle_${name}_test.cpp)
  target_link_libraries(rostest_vehicle_${name} gmm_ros ${GTEST_LIBRARIES})
  if(name STREQUAL "external_filter")  # reads config/robot_localization.yaml
    target_link_libraries(rostest_vehicle_${name} yaml-cpp)
  endif()
  target_include_directories(rostest_vehicle_${name} SYSTEM PRIVATE ${GTEST_INCLUDE_DIRS})
  # test/unit/support: the test helpers shared with the unit tests (test_georeference.h).
  target_include_directories(rostest_vehicle_${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/test/unit)
  add_dependencies(rostest_vehicle_${name} gmm_vehicle_fixture ${GMM_VEHICLE_NODELETS})
  if(TARGET tests)
    add_dependencies(tests rostest_vehicle_${name})
  endif()
  add_rostest(test/integration/vehicle_${name}.test ARGS fixture:=${GMM_VEHICLE_FIXTURE}
    DEPENDENCIES rostest_vehicle_${name})
endforeach()
# The same test node with our EKF kept but not broadcasting TF (ekf_publish_tf:=false).
add_rostest(test/integration/vehicle_ekf_no_tf.test ARGS fixture:=${GMM_VEHICLE_FIXTURE}
  DEPENDENCIES rostest_vehicle_external_filter)
