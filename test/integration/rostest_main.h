// The main() of a rostest gtest node: gtest and ROS initialised, two spinner threads serving
// the subscriptions while the test cases run, ROS shut down after them.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

namespace gmm_localization {
namespace node {

inline int runRostestMain(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}

}  // namespace node
}  // namespace gmm_localization
