#include "gmm_localization/ros/gnss_initializer_options.h"

namespace gmm_localization {
namespace node {

GnssInitializerOptions loadGnssInitializerOptions(const ParamSource& pnh) {
  GnssInitializerOptions o;
  GnssInitialPoseOptions& p = o.pose;
  p.max_horizontal_sigma_m =
      param(pnh, "max_horizontal_sigma_m", p.max_horizontal_sigma_m, 1e-3, 1000.0);
  p.unknown_sigma_m = param(pnh, "unknown_sigma_m", p.unknown_sigma_m, 1e-3, 1000.0);
  p.min_sigma_m = param(pnh, "min_sigma_m", p.min_sigma_m, 0.0, 100.0);
  p.max_heading_age_s = param(pnh, "max_heading_age_s", p.max_heading_age_s, 1e-3, 60.0);
  p.default_heading_sigma_rad =
      param(pnh, "default_heading_sigma_rad", p.default_heading_sigma_rad, 1e-4, 3.2);
  p.course_min_distance_m =
      param(pnh, "course_min_distance_m", p.course_min_distance_m, 0.1, 1000.0);
  p.course_max_gap_s = param(pnh, "course_max_gap_s", p.course_max_gap_s, 0.1, 600.0);
  p.course_sigma_rad = param(pnh, "course_sigma_rad", p.course_sigma_rad, 1e-4, 3.2);
  p.max_distance_from_origin_m =
      param(pnh, "max_distance_from_origin_m", p.max_distance_from_origin_m, 1.0, 1e6);
  requireValid("GNSS initial pose options", p.validate());
  o.map_frame = param(pnh, "map_frame", o.map_frame);
  o.base_frame = param(pnh, "base_frame", o.base_frame);
  if (o.map_frame.empty() || o.base_frame.empty() || o.map_frame == o.base_frame) {
    throw ConfigError("parameters " + pnh.resolveName("map_frame") + " and " +
                      pnh.resolveName("base_frame") + " must be non-empty and differ");
  }
  o.heading_topic = param(pnh, "heading_topic", o.heading_topic);
  o.lever_arm_from_tf = param(pnh, "lever_arm_from_tf", o.lever_arm_from_tf);
  o.retry_s = param(pnh, "retry_s", o.retry_s, 0.5, 3600.0);
  o.max_attempts = param(pnh, "max_attempts", o.max_attempts, 0, 1000000);
  o.fix_timeout_s = param(pnh, "fix_timeout_s", o.fix_timeout_s, 0.1, 3600.0);
  return o;
}

}  // namespace node
}  // namespace gmm_localization
