#pragma once
// Options of the ekf nodelet, loaded once from its private parameters (config/ekf.yaml
// documents every key) through a ParamSource (params.h: parameter server or an in-memory tree
// such as the YAML file `evaluate` reads offline). The EKF core keys are EkfOptions' member
// names (core/filter/ekf_options.h); the filter policy keys FilterPolicyOptions'
// (core/localization/localization_filter.h).

#include <string>

#include <ros/ros.h>

#include "gmm_localization/core/localization/localization_filter.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct EkfNodeOptions {
  std::string map_frame = "map";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  EkfOptions ekf;
  FilterPolicyOptions filter;

  bool use_imu = true;  ///< subscribe to `imu`
  /// subscribe to the matcher's `status` (LocalizationFilter::onMatcherMode)
  bool use_match_status = true;
  bool use_odom_twist = true;     ///< fuse the INS twist of `odom`
  double publish_rate_hz = 50.0;  ///< odometry and map->odom TF rate (wall or sim time)
  bool publish_tf = true;
  /// odom->base_link for map->odom: TF (latest); when TF has none, the newest `odom` message
  /// pose if within this age of the filter time [s].
  double odom_pose_max_age_s = 0.5;
  /// Diagnostics: an input silent for longer than this is a dropout (WARN) [s].
  double imu_timeout_s = 0.5;
  double odom_timeout_s = 0.5;
  double match_timeout_s = 3.0;
  /// GNSS input (keys under `gnss/`; filter.gnss_enabled = gnss/enabled, default false): the
  /// sensor_msgs/NavSatFix topic, placed in the map by the map index's georeference.
  std::string gnss_topic = "/gnss/fix";
  double gnss_timeout_s = 5.0;
};

/// Throws ConfigError naming the key, value and range.
EkfNodeOptions loadEkfNodeOptions(const ParamSource& pnh);
/// EkfOptions from keys named after its members (lists of 16 for the per-state arrays; 15, the
/// kinematic states only, leave the twist scale at its default).
EkfOptions loadEkfOptions(const ParamSource& nh);
/// FilterPolicyOptions (keys under `policy/`).
FilterPolicyOptions loadFilterPolicyOptions(const ParamSource& nh);
/// The GNSS keys (under `gnss/`) into o->filter, o->ekf and o's topic.
void loadGnssOptions(const ParamSource& nh, EkfNodeOptions* o);

}  // namespace node
}  // namespace gmm_localization
