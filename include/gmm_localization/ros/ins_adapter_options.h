#pragma once
// Options of the INS adapter nodelet (config/ins_adapter.yaml documents every key), loaded once
// from its private parameters through a ParamSource (params.h).
//
// The driver's conventions come from a preset (driver_preset) which the keys velocity_frame,
// body_axes and attitude, when present, override one by one:
//   rep105                     body, flu, enu            (nav_msgs/Odometry as REP-105 means it)
//   autoware_lvx               ned,  frd, ned_set_euler  (Autoware's applanix_driver lvx_client)
//   clearpath_applanix_bridge  enu,  flu, enu            (Clearpath's applanix_bridge publisher)
// docs/ros.md ("INS drivers") gives the mapping and its sources.

#include <string>

#include "gmm_localization/core/filter/ins_frames.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct InsAdapterOptions {
  std::string driver_preset = "rep105";
  InsConvention convention;
  InsOdometryOptions odometry;
  InsCovarianceDefaults covariance_defaults;
  /// The frame the driver's solution is for; empty: the message's child_frame_id (and when that
  /// is empty too, base_frame: no lever arm).
  std::string child_frame;
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  bool publish_tf = true;      ///< broadcast odom -> base_link
  int input_queue_size = 200;  ///< subscriber queue [messages]
};

/// The conventions of a driver preset (names above); false for an unknown name.
bool insDriverPreset(const std::string& name, InsConvention& out);

/// Reads and validates the options. Throws ConfigError naming the key.
InsAdapterOptions loadInsAdapterOptions(const ParamSource& pnh);

}  // namespace node
}  // namespace gmm_localization
