#include "gmm_localization/ros/ekf_node_options.h"

#include <vector>

#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {
namespace {

// A list of kTunedStateCount values, or of the kTunedStateCount - 1 kinematic ones (the lists
// before the twist scale joined the state): the twist scale then keeps its default. The GNSS
// and gyro biases have no entry (gnss_bias_*, gyro_bias_*).
std::array<double, kTunedStateCount> perState(
    const ParamSource& nh, const std::string& key,
    const std::array<double, kTunedStateCount>& defaults) {
  if (!nh.hasParam(key)) return defaults;
  const std::vector<double> v =
      param<std::vector<double>>(nh, key, std::vector<double>(defaults.begin(), defaults.end()));
  if (v.size() != static_cast<size_t>(kTunedStateCount) &&
      v.size() != static_cast<size_t>(kStateTwistScale)) {
    throw ConfigError("parameter " + nh.resolveName(key) + " must list " +
                      std::to_string(kTunedStateCount) +
                      " values (x y z roll pitch yaw vx vy vz wx "
                      "wy wz ax ay az twist_scale; without twist_scale: the default), it has " +
                      std::to_string(v.size()));
  }
  std::array<double, kTunedStateCount> out = defaults;
  std::copy(v.begin(), v.end(), out.begin());
  return out;
}

}  // namespace

EkfOptions loadEkfOptions(const ParamSource& nh) {
  EkfOptions o;
  // Ranges are checked by EkfOptions::validate() (which names key, value and range).
  o.history_length_s = param(nh, "history_length_s", o.history_length_s);
  o.max_history_entries = param(nh, "max_history_entries", o.max_history_entries);
  o.time_backwards_tolerance_s =
      param(nh, "time_backwards_tolerance_s", o.time_backwards_tolerance_s);
  o.stale_reset_count = param(nh, "stale_reset_count", o.stale_reset_count);
  o.time_backwards_reset_s = param(nh, "time_backwards_reset_s", o.time_backwards_reset_s);
  o.max_prediction_gap_s = param(nh, "max_prediction_gap_s", o.max_prediction_gap_s);
  o.max_prediction_step_s = param(nh, "max_prediction_step_s", o.max_prediction_step_s);
  o.gravity_mps2 = param(nh, "gravity_mps2", o.gravity_mps2);
  o.min_measurement_variance = param(nh, "min_measurement_variance", o.min_measurement_variance);
  o.process_noise_density = perState(nh, "process_noise_density", o.process_noise_density);
  o.initial_variance = perState(nh, "initial_variance", o.initial_variance);
  o.pose_gate_probability = param(nh, "pose_gate_probability", o.pose_gate_probability);
  o.twist_gate_probability = param(nh, "twist_gate_probability", o.twist_gate_probability);
  o.imu_gate_probability = param(nh, "imu_gate_probability", o.imu_gate_probability);
  o.imu_use_orientation = param(nh, "imu_use_orientation", o.imu_use_orientation);
  o.imu_use_angular_velocity = param(nh, "imu_use_angular_velocity", o.imu_use_angular_velocity);
  o.imu_use_linear_acceleration =
      param(nh, "imu_use_linear_acceleration", o.imu_use_linear_acceleration);
  const std::string gravity = param<std::string>(nh, "imu_gravity_removal", "state_estimate");
  if (gravity == "state_estimate") {
    o.imu_gravity_removal = GravityRemoval::kStateEstimate;
  } else if (gravity == "measured_orientation") {
    o.imu_gravity_removal = GravityRemoval::kMeasuredOrientation;
  } else {
    throw ConfigError("parameter " + nh.resolveName("imu_gravity_removal") + " = '" + gravity +
                      "' must be state_estimate or measured_orientation");
  }
  o.twist_use_linear = param(nh, "twist_use_linear", o.twist_use_linear);
  o.twist_use_angular = param(nh, "twist_use_angular", o.twist_use_angular);
  o.estimate_twist_scale = param(nh, "estimate_twist_scale", o.estimate_twist_scale);
  o.estimate_gnss_bias = param(nh, "estimate_gnss_bias", o.estimate_gnss_bias);
  o.gnss_bias_sigma_m = param(nh, "gnss_bias_sigma_m", o.gnss_bias_sigma_m);
  o.gnss_bias_tau_s = param(nh, "gnss_bias_tau_s", o.gnss_bias_tau_s);
  o.estimate_gyro_bias = param(nh, "estimate_gyro_bias", o.estimate_gyro_bias);
  o.gyro_bias_sigma_radps = param(nh, "gyro_bias_sigma_radps", o.gyro_bias_sigma_radps);
  o.gyro_bias_random_walk = param(nh, "gyro_bias_random_walk", o.gyro_bias_random_walk);
  const Status valid = o.validate();
  if (!valid) throw ConfigError(valid.error());
  return o;
}

FilterPolicyOptions loadFilterPolicyOptions(const ParamSource& parent) {
  const ParamSource nh = parent.child("policy");
  FilterPolicyOptions o;
  const std::vector<bool> mask_default(o.match_mask.begin(), o.match_mask.end());
  const std::vector<bool> mask = param<std::vector<bool>>(nh, "match_mask", mask_default);
  if (mask.size() != 6) {
    throw ConfigError("parameter " + nh.resolveName("match_mask") +
                      " must list 6 booleans (x y z roll pitch yaw)");
  }
  std::copy(mask.begin(), mask.end(), o.match_mask.begin());
  o.initialize_from_match = param(nh, "initialize_from_match", o.initialize_from_match);
  o.gate_lockout_count = param(nh, "gate_lockout_count", o.gate_lockout_count, 1, 1000000);
  o.relocalize_sigma_xy_m =
      param(nh, "relocalize_sigma_xy_m", o.relocalize_sigma_xy_m, 1e-3, 1000.0);
  o.relocalize_sigma_yaw_rad =
      param(nh, "relocalize_sigma_yaw_rad", o.relocalize_sigma_yaw_rad, 1e-4, 3.2);
  o.max_start_sigma_yaw_rad =
      param(nh, "max_start_sigma_yaw_rad", o.max_start_sigma_yaw_rad, 1e-4, 1e3);
  o.lost_sigma_xy_m = param(nh, "lost_sigma_xy_m", o.lost_sigma_xy_m, 1e-3, 1e4);
  o.lost_sigma_yaw_rad = param(nh, "lost_sigma_yaw_rad", o.lost_sigma_yaw_rad, 1e-4, 3.2);
  o.unknown_z_sigma_m = param(nh, "unknown_z_sigma_m", o.unknown_z_sigma_m, 1e-3, 1000.0);
  o.unknown_tilt_sigma_rad =
      param(nh, "unknown_tilt_sigma_rad", o.unknown_tilt_sigma_rad, 1e-4, 3.2);
  o.forward_jump_reset_count =
      param(nh, "forward_jump_reset_count", o.forward_jump_reset_count, 1, 1000000);
  o.twist_linear_min_sigma_mps =
      param(nh, "twist_linear_min_sigma_mps", o.twist_linear_min_sigma_mps, 0.0, 100.0);
  o.twist_linear_sigma_per_speed =
      param(nh, "twist_linear_sigma_per_speed", o.twist_linear_sigma_per_speed, 0.0, 1.0);
  MeasurementDefaults& d = o.defaults;
  d.imu_orientation_sigma_rad =
      param(nh, "defaults/imu_orientation_sigma_rad", d.imu_orientation_sigma_rad, 1e-6, 10.0);
  d.imu_angular_velocity_sigma_radps = param(nh, "defaults/imu_angular_velocity_sigma_radps",
                                             d.imu_angular_velocity_sigma_radps, 1e-6, 10.0);
  d.imu_linear_acceleration_sigma_mps2 = param(nh, "defaults/imu_linear_acceleration_sigma_mps2",
                                               d.imu_linear_acceleration_sigma_mps2, 1e-6, 100.0);
  d.twist_linear_sigma_mps =
      param(nh, "defaults/twist_linear_sigma_mps", d.twist_linear_sigma_mps, 1e-6, 100.0);
  d.twist_angular_sigma_radps =
      param(nh, "defaults/twist_angular_sigma_radps", d.twist_angular_sigma_radps, 1e-6, 10.0);
  requireValid("ekf policy options", o.validate());
  return o;
}

void loadGnssOptions(const ParamSource& nh, EkfNodeOptions* o) {
  GnssPositionOptions& g = o->filter.gnss;
  o->filter.gnss_enabled = param(nh, "enabled", o->filter.gnss_enabled);
  o->gnss_topic = param<std::string>(nh, "topic", o->gnss_topic);
  o->gnss_timeout_s = param(nh, "timeout_s", o->gnss_timeout_s, 0.001, 3600.0);
  o->ekf.gnss_gate_probability =
      param(nh, "gate_probability", o->ekf.gnss_gate_probability, 1e-9, 1.0);
  g.unknown_sigma_m = param(nh, "unknown_sigma_m", g.unknown_sigma_m, 1e-3, 1000.0);
  g.min_sigma_m = param(nh, "min_sigma_m", g.min_sigma_m, 0.0, 1000.0);
  g.max_horizontal_sigma_m =
      param(nh, "max_horizontal_sigma_m", g.max_horizontal_sigma_m, 1e-3, 1e4);
  g.use_z = param(nh, "use_z", g.use_z);
  if (o->gnss_topic.empty()) {
    throw ConfigError("parameter " + nh.resolveName("topic") + " must not be empty");
  }
}

EkfNodeOptions loadEkfNodeOptions(const ParamSource& pnh) {
  EkfNodeOptions o;
  o.map_frame = param<std::string>(pnh, "map_frame", o.map_frame);
  o.odom_frame = param<std::string>(pnh, "odom_frame", o.odom_frame);
  o.base_frame = param<std::string>(pnh, "base_frame", o.base_frame);
  if (o.map_frame.empty() || o.odom_frame.empty() || o.base_frame.empty()) {
    throw ConfigError("parameters map_frame, odom_frame and base_frame must not be empty");
  }
  o.ekf = loadEkfOptions(pnh);
  o.filter = loadFilterPolicyOptions(pnh);
  o.use_imu = param(pnh, "use_imu", o.use_imu);
  o.use_match_status = param(pnh, "use_match_status", o.use_match_status);
  o.use_odom_twist = param(pnh, "use_odom_twist", o.use_odom_twist);
  o.publish_rate_hz = param(pnh, "publish_rate_hz", o.publish_rate_hz, 0.1, 1000.0);
  o.publish_tf = param(pnh, "publish_tf", o.publish_tf);
  o.odom_pose_max_age_s = param(pnh, "odom_pose_max_age_s", o.odom_pose_max_age_s, 0.0, 60.0);
  o.imu_timeout_s = param(pnh, "imu_timeout_s", o.imu_timeout_s, 0.001, 3600.0);
  o.odom_timeout_s = param(pnh, "odom_timeout_s", o.odom_timeout_s, 0.001, 3600.0);
  o.match_timeout_s = param(pnh, "match_timeout_s", o.match_timeout_s, 0.001, 3600.0);
  loadGnssOptions(pnh.child("gnss"), &o);
  return o;
}

}  // namespace node
}  // namespace gmm_localization
