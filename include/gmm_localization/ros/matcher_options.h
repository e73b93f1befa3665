#pragma once
// Options of the matcher nodelet, loaded once from its private parameters (config/matcher.yaml
// documents every key). The loaders read a ParamSource (params.h): the nodelet passes its private
// NodeHandle, the offline `evaluate` tool the same YAML file parsed into a tree, so both read
// the same keys with the same checks. The registration and policy loaders are public too.

#include <string>

#include <ros/ros.h>

#include "gmm_localization/core/localization/localizer_pipeline.h"
#include "gmm_localization/core/localization/match_policy.h"
#include "gmm_localization/core/localization/match_session.h"
#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/matching/traversal_image.h"
#include "gmm_localization/ros/ekf_node_options.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct MatcherOptions {
  std::string map_frame = "map";
  std::string base_frame = "base_link";
  RegistrationOptions registration;
  LocalizationPolicyOptions policy;
  MatchMethodOptions method;  ///< `method` and `reflectivity/*`: the map layer matched

  /// deskew, deskew_twist_max_gap_s, odometry_buffer_s, odometry_max_extrapolation_s,
  /// time_backwards_tolerance_s, scan_queue_size and initial_pose/on_reset (the keys of the
  /// same names): the MatchSession's options, copied as one into LocalizerPipelineOptions.
  MatchSessionOptions session;

  /// Configured initial pose (unattended start): searched with its window at the first scan.
  bool initial_pose_enabled = false;
  Pose6 initial_pose;  ///< x, y, z [m], yaw [rad] (roll, pitch 0)
  bool initial_pose_z_known = true;
  double initial_pose_half_xy_m = 12.5;           ///< its window [m]
  double initial_pose_half_heading_rad = 0.2618;  ///< [rad]

  std::string obstacles_frame = "base_link";  ///< base_frame or map_frame
  double classified_max_mahalanobis = 10.0;   ///< clamp of the `mahalanobis` field
  TraversalImageOptions traversal;

  /// ROS subscriber queue of the merged clouds. Larger than the session's scan queue so that,
  /// under load, scans are dropped in the session's queue (counted, reported in the next
  /// status's dropped_scans) and not silently by roscpp before the matcher sees them.
  int scan_subscriber_queue_size = 10;
  double expected_scan_rate_hz = 10.0;  ///< diagnostics: scans below half this rate warn
  double min_accepted_share = 0.5;      ///< diagnostics: warn below this share (last 50)
};

/// Throws ConfigError naming the key, value and range.
MatcherOptions loadMatcherOptions(const ParamSource& pnh);
/// Keys under `registration/` (filter, search, hill climb, covariance, obstacles).
RegistrationOptions loadRegistrationOptions(const ParamSource& nh);
/// Keys under `window/`, `acceptance/`, `covariance/`, `relocalization/`.
LocalizationPolicyOptions loadLocalizationPolicyOptions(const ParamSource& nh);

/// The LocalizerPipeline options equivalent to a matcher + ekf nodelet pair with these options
/// (for `evaluate`: load both with the loaders above from the same YAML files): the session
/// options (scan queue included) are copied as one. The configured initial pose is not
/// included: call LocalizerPipeline::setConfiguredPose with configuredPoseWindow() when
/// matcher.initial_pose_enabled.
LocalizerPipelineOptions pipelineOptions(const MatcherOptions& matcher, const EkfNodeOptions& ekf);
/// The configured initial pose's own window.
WindowExtent configuredPoseWindow(const MatcherOptions& matcher);

}  // namespace node
}  // namespace gmm_localization
