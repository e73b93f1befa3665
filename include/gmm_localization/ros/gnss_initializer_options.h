#pragma once
// Options of the GNSS initializer nodelet (config/gnss_initializer.yaml documents every key),
// loaded once from its private parameters through a ParamSource (params.h).

#include <string>

#include "gmm_localization/core/localization/gnss_initial_pose.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct GnssInitializerOptions {
  GnssInitialPoseOptions pose;  ///< antenna_in_base comes from TF, not from parameters
  std::string map_frame = "map";
  std::string base_frame = "base_link";
  /// sensor_msgs/Imu whose orientation is the vehicle's ENU attitude (a dual-antenna receiver or
  /// the INS); empty: the heading is the course over ground.
  std::string heading_topic;
  bool lever_arm_from_tf = true;  ///< false: the fix is taken as base_link's position
  /// A pose sent without an accepted match within retry_s [s of ROS time] is sent again from a
  /// newer fix; 0 attempts limit = no limit.
  double retry_s = 15.0;
  int max_attempts = 0;
  double fix_timeout_s = 5.0;  ///< no fix for this long: a WARN naming the topic
};

/// Throws ConfigError naming the parameter on a bad value.
GnssInitializerOptions loadGnssInitializerOptions(const ParamSource& pnh);

}  // namespace node
}  // namespace gmm_localization
