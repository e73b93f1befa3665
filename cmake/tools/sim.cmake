# Simulator tools: `simulate` (rosbag and KITTI output) and `sim_validate` (comparison with
# real HDL-32E revolutions). The simulator library itself (gmm_sim) stays ROS-free; only the bag
# writer here uses rosbag and the standard message types.
gmm_add_tool(simulate
  SOURCES src/tools/simulate/simulate.cpp src/tools/simulate/simulate_options.cpp src/tools/simulate/simulate_help.cpp
          src/tools/simulate/simulate_bag_writer.cpp src/tools/simulate/simulate_imperfection_options.cpp
          src/tools/simulate/simulate_gnss.cpp
  LIBS gmm_sim ${catkin_LIBRARIES})
target_include_directories(simulate SYSTEM PRIVATE ${catkin_INCLUDE_DIRS})

gmm_add_tool(sim_validate
  SOURCES src/tools/sim_validate/sim_validate.cpp src/tools/sim_validate/sim_validate_stats.cpp
  LIBS gmm_sim)
