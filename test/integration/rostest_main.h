// The main() of a rostest gtest node: gtest and ROS initialised, two spinner threads serving
// the subscriptions while the test cases run, ROS shut down after them.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cstdio>

namespace gmm_localization {
namespace node {

inline int runRostestMain(int argc, char** argv, const char* node_name) {
  // Line-buffered: what a test printed survives a crash of the test process.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
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
