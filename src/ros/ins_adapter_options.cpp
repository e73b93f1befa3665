#include "gmm_localization/ros/ins_adapter_options.h"

namespace gmm_localization {
namespace node {
namespace {

template <typename Enum>
Enum enumParam(const ParamSource& pnh, const std::string& key, Enum value,
               bool (*parse)(const std::string&, Enum&), const char* allowed) {
  if (!pnh.hasParam(key)) return value;
  const std::string name = param<std::string>(pnh, key, "");
  if (!parse(name, value)) {
    throw ConfigError("parameter " + pnh.resolveName(key) + " = '" + name + "' must be " + allowed);
  }
  return value;
}

std::string nonEmpty(const ParamSource& pnh, const std::string& key, const std::string& value) {
  const std::string v = param<std::string>(pnh, key, value);
  if (v.empty()) throw ConfigError("parameter " + pnh.resolveName(key) + " must not be empty");
  return v;
}

}  // namespace

bool insDriverPreset(const std::string& name, InsConvention& out) {
  InsConvention c;
  if (name == "rep105") {
    c.velocity_frame = InsVelocityFrame::kBody;
    c.body_axes = InsBodyAxes::kFlu;
    c.attitude = InsAttitude::kEnu;
  } else if (name == "autoware_lvx") {
    c.velocity_frame = InsVelocityFrame::kNed;
    c.body_axes = InsBodyAxes::kFrd;
    c.attitude = InsAttitude::kNedSetEuler;
  } else if (name == "clearpath_applanix_bridge") {
    c.velocity_frame = InsVelocityFrame::kEnu;
    c.body_axes = InsBodyAxes::kFlu;
    c.attitude = InsAttitude::kEnu;
  } else {
    return false;
  }
  out = c;
  return true;
}

InsAdapterOptions loadInsAdapterOptions(const ParamSource& pnh) {
  InsAdapterOptions o;
  o.driver_preset = param<std::string>(pnh, "driver_preset", o.driver_preset);
  if (!insDriverPreset(o.driver_preset, o.convention)) {
    throw ConfigError("parameter " + pnh.resolveName("driver_preset") + " = '" + o.driver_preset +
                      "' must be rep105, autoware_lvx or clearpath_applanix_bridge");
  }
  InsConvention& c = o.convention;
  c.velocity_frame =
      enumParam(pnh, "velocity_frame", c.velocity_frame, parseInsVelocityFrame, "body, enu or ned");
  c.body_axes = enumParam(pnh, "body_axes", c.body_axes, parseInsBodyAxes, "flu or frd");
  c.attitude =
      enumParam(pnh, "attitude", c.attitude, parseInsAttitude, "enu, ned or ned_set_euler");
  requireValid("INS conventions", c.validate());

  o.odometry.pose_source = enumParam(pnh, "pose_source", o.odometry.pose_source, parseInsPoseSource,
                                     "dead_reckoning or driver");
  o.odometry.max_gap_s = param(pnh, "max_gap_s", o.odometry.max_gap_s, 1e-3, 3600.0);
  o.odometry.backwards_reset_s =
      param(pnh, "backwards_reset_s", o.odometry.backwards_reset_s, 1e-3, 3600.0);
  requireValid("INS odometry options", o.odometry.validate());

  o.covariance_defaults.linear_sigma_mps =
      param(pnh, "default_linear_sigma_mps", o.covariance_defaults.linear_sigma_mps, 1e-6, 100.0);
  o.covariance_defaults.angular_sigma_radps = param(
      pnh, "default_angular_sigma_radps", o.covariance_defaults.angular_sigma_radps, 1e-6, 10.0);

  o.child_frame = param<std::string>(pnh, "child_frame", o.child_frame);
  o.odom_frame = nonEmpty(pnh, "odom_frame", o.odom_frame);
  o.base_frame = nonEmpty(pnh, "base_frame", o.base_frame);
  if (o.odom_frame == o.base_frame) {
    throw ConfigError("parameters odom_frame and base_frame must differ ('" + o.odom_frame + "')");
  }
  o.publish_tf = param(pnh, "publish_tf", o.publish_tf);
  o.input_queue_size = param(pnh, "input_queue_size", o.input_queue_size, 1, 10000);
  return o;
}

}  // namespace node
}  // namespace gmm_localization
