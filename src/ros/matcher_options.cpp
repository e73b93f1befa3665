#include "gmm_localization/ros/matcher_options.h"
#include <cmath>

#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {
namespace {

constexpr double kBig = 1e9;

}  // namespace

RegistrationOptions loadRegistrationOptions(const ParamSource& parent) {
  const ParamSource nh = parent.child("registration");
  RegistrationOptions o;
  ScanFilterOptions& f = o.filter;
  f.min_range_m = param(nh, "filter/min_range_m", f.min_range_m, 0.0, 1000.0);
  f.max_range_m = param(nh, "filter/max_range_m", f.max_range_m, 0.0, 1000.0);
  f.min_height_m = param(nh, "filter/min_height_m", f.min_height_m, -1000.0, 1000.0);
  f.max_height_m = param(nh, "filter/max_height_m", f.max_height_m, -1000.0, 1000.0);
  f.voxel_m = param(nh, "filter/voxel_m", f.voxel_m, 0.0, 10.0);
  f.max_points = static_cast<size_t>(
      param(nh, "filter/max_points", static_cast<int>(f.max_points), 0, 100000000));
  f.ground_share = param(nh, "filter/ground_share", f.ground_share, 0.0, 1.0);
  f.ground_cell_m = param(nh, "filter/ground_cell_m", f.ground_cell_m, 0.1, 100.0);
  f.ground_band_m = param(nh, "filter/ground_band_m", f.ground_band_m, 0.0, 10.0);
  o.refine_max_points = static_cast<size_t>(
      param(nh, "refine_max_points", static_cast<int>(o.refine_max_points), 10, 10000000));
  o.heading_step_rad = param(nh, "heading_step_rad", o.heading_step_rad, 1e-4, 0.2);
  o.z_search_m = param(nh, "z_search_m", o.z_search_m, 0.0, 20.0);
  o.exhaustive = param(nh, "exhaustive", o.exhaustive);
  o.branch_and_bound.prior_as_incumbent =
      param(nh, "prior_as_incumbent", o.branch_and_bound.prior_as_incumbent);
  HillClimbOptions& h = o.hill_climb;
  h.max_xy_m = param(nh, "hill_climb/max_xy_m", h.max_xy_m, 0.0, 10.0);
  h.max_yaw_rad = param(nh, "hill_climb/max_yaw_rad", h.max_yaw_rad, 0.0, 1.0);
  h.max_z_m = param(nh, "hill_climb/max_z_m", h.max_z_m, 0.0, 10.0);
  h.max_roll_pitch_rad = param(nh, "hill_climb/max_roll_pitch_rad", h.max_roll_pitch_rad, 0.0, 1.0);
  h.max_evaluations = param(nh, "hill_climb/max_evaluations", h.max_evaluations, 1, 100000);
  CovarianceOptions& c = o.covariance;
  c.radius_m = param(nh, "covariance/radius_m", c.radius_m, 0.01, 100.0);
  c.heading_radius = param(nh, "covariance/heading_radius", c.heading_radius, 0, 1000);
  c.temperature_per_point =
      param(nh, "covariance/temperature_per_point", c.temperature_per_point, 1e-6, 100.0);
  c.min_sigma_xy_m = param(nh, "covariance/min_sigma_xy_m", c.min_sigma_xy_m, 1e-6, 100.0);
  c.min_sigma_yaw_rad = param(nh, "covariance/min_sigma_yaw_rad", c.min_sigma_yaw_rad, 1e-7, 3.2);
  c.edge_mass_limit = param(nh, "covariance/edge_mass_limit", c.edge_mass_limit, 1e-6, 1.0);
  c.max_points = static_cast<size_t>(
      param(nh, "covariance/max_points", static_cast<int>(c.max_points), 0, 1000000));
  CertificateOptions& ce = o.certificate;
  ce.enabled = param(nh, "certificate/enabled", ce.enabled);
  ce.exclusion_radius_m =
      param(nh, "certificate/exclusion_radius_m", ce.exclusion_radius_m, 1e-3, 1e4);
  ce.exclusion_heading_rad =
      param(nh, "certificate/exclusion_heading_rad", ce.exclusion_heading_rad, 1e-4, 3.15);
  ce.margin_per_point = param(nh, "certificate/margin_per_point", ce.margin_per_point, 0.0, 100.0);
  ce.separation_depth_per_point = param(nh, "certificate/separation_depth_per_point",
                                        ce.separation_depth_per_point, 0.0, 100.0);
  ce.max_evaluations = static_cast<int64_t>(
      param(nh, "certificate/max_evaluations", static_cast<int>(ce.max_evaluations), 1, 100000000));
  ce.wide_min_half_xy_m =
      param(nh, "certificate/wide_min_half_xy_m", ce.wide_min_half_xy_m, 1e-3, 1e4);
  ce.wide_max_evaluations =
      static_cast<int64_t>(param(nh, "certificate/wide_max_evaluations",
                                 static_cast<int>(ce.wide_max_evaluations), 1, 100000000));
  ce.global_max_evaluations =
      static_cast<int64_t>(param(nh, "certificate/global_max_evaluations",
                                 static_cast<int>(ce.global_max_evaluations), 1, 1000000000));
  o.interval_search_min_headings =
      param(nh, "interval_search_min_headings", o.interval_search_min_headings, 1, 100000);
  GlobalSearchOptions& g = o.global;
  g.root_heading_levels = param(nh, "global/root_heading_levels", g.root_heading_levels, 0, 11);
  g.max_points = static_cast<size_t>(
      param(nh, "global/max_points", static_cast<int>(g.max_points), 0, 1000000));
  g.max_evaluations = static_cast<int64_t>(
      param(nh, "global/max_evaluations", static_cast<int>(g.max_evaluations), 0, 1000000000));
  g.min_score_per_point =
      param(nh, "global/min_score_per_point", g.min_score_per_point, -1000.0, 1000.0);
  g.confirm_half_xy_m = param(nh, "global/confirm_half_xy_m", g.confirm_half_xy_m, 0.01, 12.5);
  g.threads = param(nh, "global/threads", g.threads, 0, 64);
  g.confirm_half_heading_rad =
      param(nh, "global/confirm_half_heading_rad", g.confirm_half_heading_rad, 0.001, 0.5);
  o.classify_obstacles = param(nh, "classify_obstacles", o.classify_obstacles);
  o.obstacles.mahalanobis_threshold =
      param(nh, "obstacles/mahalanobis_threshold", o.obstacles.mahalanobis_threshold, 0.0, 1000.0);
  o.min_map_coverage = param(nh, "min_map_coverage", o.min_map_coverage, 0.0, 1.0);
  o.threads = param(nh, "threads", o.threads, 0, TaskPool::kMaxThreads);
  requireValid("registration options", o.validate());
  return o;
}

LocalizationPolicyOptions loadLocalizationPolicyOptions(const ParamSource& nh) {
  LocalizationPolicyOptions o;
  WindowPolicyOptions& w = o.window;
  w.sigma_multiplier = param(nh, "window/sigma_multiplier", w.sigma_multiplier, 0.5, 10.0);
  w.min_half_xy_m = param(nh, "window/min_half_xy_m", w.min_half_xy_m, 0.2, 100.0);
  w.max_half_xy_m = param(nh, "window/max_half_xy_m", w.max_half_xy_m, 0.2, 100.0);
  w.min_half_heading_rad =
      param(nh, "window/min_half_heading_rad", w.min_half_heading_rad, 0.0, 1.6);
  w.max_half_heading_rad =
      param(nh, "window/max_half_heading_rad", w.max_half_heading_rad, 0.0, 1.6);
  w.wide_half_xy_m = param(nh, "window/wide_half_xy_m", w.wide_half_xy_m, 0.2, 100.0);
  w.wide_half_heading_rad =
      param(nh, "window/wide_half_heading_rad", w.wide_half_heading_rad, 0.0, 1.6);
  w.unknown_z_search_m = param(nh, "window/unknown_z_search_m", w.unknown_z_search_m, 0.0, 20.0);
  w.global_max_half_xy_m =
      param(nh, "window/global_max_half_xy_m", w.global_max_half_xy_m, 0.2, 100.0);
  w.global_max_half_heading_rad =
      param(nh, "window/global_max_half_heading_rad", w.global_max_half_heading_rad, 0.0, M_PI);
  w.global_widen_factor = param(nh, "window/global_widen_factor", w.global_widen_factor, 1.0, 4.0);
  w.global_widest_half_xy_m =
      param(nh, "window/global_widest_half_xy_m", w.global_widest_half_xy_m, 0.2, 200.0);
  w.interim_half_xy_m = param(nh, "window/interim_half_xy_m", w.interim_half_xy_m, 0.2, 100.0);
  w.interim_half_heading_rad =
      param(nh, "window/interim_half_heading_rad", w.interim_half_heading_rad, 0.0, 1.6);
  AcceptancePolicyOptions& a = o.acceptance;
  a.min_log_likelihood_per_point = param(nh, "acceptance/min_log_likelihood_per_point",
                                         a.min_log_likelihood_per_point, -100.0, 10.0);
  a.min_map_coverage = param(nh, "acceptance/min_map_coverage", a.min_map_coverage, 0.0, 1.0);
  a.max_sigma_xy_m = param(nh, "acceptance/max_sigma_xy_m", a.max_sigma_xy_m, 0.0, 1000.0);
  a.max_sigma_yaw_rad = param(nh, "acceptance/max_sigma_yaw_rad", a.max_sigma_yaw_rad, 0.0, 10.0);
  a.reject_on_window_edge = param(nh, "acceptance/reject_on_window_edge", a.reject_on_window_edge);
  a.require_certificate = param(nh, "acceptance/require_certificate", a.require_certificate);
  a.require_certificate_wide =
      param(nh, "acceptance/require_certificate_wide", a.require_certificate_wide);
  a.max_likelihood_drop =
      param(nh, "acceptance/max_likelihood_drop", a.max_likelihood_drop, 0.0, 100.0);
  a.likelihood_history = param(nh, "acceptance/likelihood_history", a.likelihood_history, 5, 10000);
  PoseCovariancePolicyOptions& c = o.covariance;
  c.use_search_covariance = param(nh, "covariance/use_search_covariance", c.use_search_covariance);
  c.search_covariance_scale =
      param(nh, "covariance/search_covariance_scale", c.search_covariance_scale, 1e-3, 1e3);
  c.fixed_sigma_xy_m = param(nh, "covariance/fixed_sigma_xy_m", c.fixed_sigma_xy_m, 1e-4, 100.0);
  c.fixed_sigma_yaw_rad =
      param(nh, "covariance/fixed_sigma_yaw_rad", c.fixed_sigma_yaw_rad, 1e-5, 3.2);
  c.min_sigma_xy_m = param(nh, "covariance/min_sigma_xy_m", c.min_sigma_xy_m, 1e-4, 100.0);
  c.min_sigma_yaw_rad = param(nh, "covariance/min_sigma_yaw_rad", c.min_sigma_yaw_rad, 1e-5, 3.2);
  c.sigma_z_m = param(nh, "covariance/sigma_z_m", c.sigma_z_m, 1e-4, 100.0);
  c.sigma_roll_pitch_rad =
      param(nh, "covariance/sigma_roll_pitch_rad", c.sigma_roll_pitch_rad, 1e-5, 3.2);
  c.uncertified_min_sigma_xy_m = param(nh, "covariance/uncertified_min_sigma_xy_m",
                                       c.uncertified_min_sigma_xy_m, 1e-4, 1000.0);
  c.uncertified_min_sigma_yaw_rad = param(nh, "covariance/uncertified_min_sigma_yaw_rad",
                                          c.uncertified_min_sigma_yaw_rad, 1e-5, 3.2);
  RelocalizationPolicyOptions& r = o.relocalization;
  r.max_consecutive_rejections = param(nh, "relocalization/max_consecutive_rejections",
                                       r.max_consecutive_rejections, 1, 1000000);
  r.max_posterior_age_s =
      param(nh, "relocalization/max_posterior_age_s", r.max_posterior_age_s, 0.0, 60.0);
  r.max_previous_match_age_s =
      param(nh, "relocalization/max_previous_match_age_s", r.max_previous_match_age_s, 0.0, 600.0);
  r.previous_match_sigma_growth_mps = param(nh, "relocalization/previous_match_sigma_growth_mps",
                                            r.previous_match_sigma_growth_mps, 0.0, 100.0);
  r.max_stale_prior_age_s =
      param(nh, "relocalization/max_stale_prior_age_s", r.max_stale_prior_age_s, 0.0, 1e6);
  r.match_history_s = param(nh, "relocalization/match_history_s", r.match_history_s, 0.0, 86400.0);
  r.recall_max_gap_s = param(nh, "relocalization/recall_max_gap_s", r.recall_max_gap_s, 0.0, 10.0);
  r.lost_after_rejections =
      param(nh, "relocalization/lost_after_rejections", r.lost_after_rejections, 0, 1000000);
  r.lost_after_collapses =
      param(nh, "relocalization/lost_after_collapses", r.lost_after_collapses, 0, 1000000);
  r.jump_posterior_max_gap_m = param(nh, "relocalization/jump_posterior_max_gap_m",
                                     r.jump_posterior_max_gap_m, 0.01, 1000.0);
  r.lost_after_wide_rejections = param(nh, "relocalization/lost_after_wide_rejections",
                                       r.lost_after_wide_rejections, 0, 1000000);
  requireValid("localization policy options", o.validate());
  return o;
}

MatchMethodOptions loadMatchMethodOptions(const ParamSource& pnh) {
  MatchMethodOptions o;
  const std::string method = param<std::string>(pnh, "method", matchMethodName(o.method));
  if (!parseMatchMethod(method, &o.method)) {
    throw ConfigError("parameter " + pnh.resolveName("method") + " = '" + method +
                      "' must be height (the paper's), reflectivity (the baseline; the map "
                      "server must serve the map's reflectivity layer) or fused (both summed: "
                      "the reflectivity layer from a second map server on "
                      "reflectivity/map_*, localization.launch method:=fused)");
  }
  ReflectivityLayerOptions& r = o.reflectivity;
  r.metres_per_unit = param(pnh, "reflectivity/metres_per_unit", r.metres_per_unit, 1e-4, 1.0);
  r.ground_height_m = param(pnh, "reflectivity/ground_height_m", r.ground_height_m, -10.0, 10.0);
  r.ground_min_m = param(pnh, "reflectivity/ground_min_m", r.ground_min_m, -2.0, 2.0);
  r.ground_max_m = param(pnh, "reflectivity/ground_max_m", r.ground_max_m, -2.0, 2.0);
  r.max_range_m = param(pnh, "reflectivity/max_range_m", r.max_range_m, 1.0, 200.0);
  requireValid("matcher method options", o.validate());
  return o;
}

MatcherOptions loadMatcherOptions(const ParamSource& pnh) {
  MatcherOptions o;
  o.map_frame = param<std::string>(pnh, "map_frame", o.map_frame);
  o.base_frame = param<std::string>(pnh, "base_frame", o.base_frame);
  if (o.map_frame.empty() || o.base_frame.empty()) {
    throw ConfigError("parameters map_frame and base_frame must not be empty");
  }
  o.registration = loadRegistrationOptions(pnh);
  o.policy = loadLocalizationPolicyOptions(pnh);
  o.method = loadMatchMethodOptions(pnh);
  MatchSessionOptions& s = o.session;
  s.deskew = param(pnh, "deskew", s.deskew);
  s.deskew_twist_max_gap_s =
      param(pnh, "deskew_twist_max_gap_s", s.deskew_twist_max_gap_s, 0.0, 10.0);
  s.odometry_buffer_s = param(pnh, "odometry_buffer_s", s.odometry_buffer_s, 0.1, 3600.0);
  s.odometry_max_extrapolation_s =
      param(pnh, "odometry_max_extrapolation_s", s.odometry_max_extrapolation_s, 0.0, 10.0);
  s.time_backwards_tolerance_s =
      param(pnh, "time_backwards_tolerance_s", s.time_backwards_tolerance_s, 0.0, kBig);
  s.max_scan_ahead_s = param(pnh, "max_scan_ahead_s", s.max_scan_ahead_s, 0.0, kBig);
  s.max_scan_age_s = param(pnh, "max_scan_age_s", s.max_scan_age_s, 0.0, kBig);
  s.scan_queue_size = param(pnh, "scan_queue_size", s.scan_queue_size, 1, 100);

  o.initial_pose_enabled = param(pnh, "initial_pose/enabled", o.initial_pose_enabled);
  o.initial_pose.x = param(pnh, "initial_pose/x", o.initial_pose.x, -kBig, kBig);
  o.initial_pose.y = param(pnh, "initial_pose/y", o.initial_pose.y, -kBig, kBig);
  o.initial_pose.z = param(pnh, "initial_pose/z", o.initial_pose.z, -kBig, kBig);
  o.initial_pose.yaw = param(pnh, "initial_pose/yaw", o.initial_pose.yaw, -10.0, 10.0);
  o.initial_pose_z_known = param(pnh, "initial_pose/z_known", o.initial_pose_z_known);
  o.initial_pose_half_xy_m =
      param(pnh, "initial_pose/window_half_xy_m", o.initial_pose_half_xy_m, 0.2, 100.0);
  o.initial_pose_half_heading_rad =
      param(pnh, "initial_pose/window_half_heading_rad", o.initial_pose_half_heading_rad, 0.0, 3.2);
  s.configured_pose_on_reset = param(pnh, "initial_pose/on_reset", s.configured_pose_on_reset);
  requireValid("matcher session options", s.validate());

  o.obstacles_frame = param<std::string>(pnh, "obstacles_frame", o.obstacles_frame);
  if (o.obstacles_frame != o.base_frame && o.obstacles_frame != o.map_frame) {
    throw ConfigError("parameter " + pnh.resolveName("obstacles_frame") + " = '" +
                      o.obstacles_frame + "' must be base_frame ('" + o.base_frame +
                      "') or map_frame ('" + o.map_frame + "')");
  }
  o.classified_max_mahalanobis =
      param(pnh, "classified_max_mahalanobis", o.classified_max_mahalanobis, 0.1, 1e6);
  o.traversal.max_width_px =
      param(pnh, "traversal/max_width_px", o.traversal.max_width_px, 16, 16384);
  o.traversal.max_tile_px = param(pnh, "traversal/max_tile_px", o.traversal.max_tile_px, 4, 4096);
  o.traversal.gap_px = param(pnh, "traversal/gap_px", o.traversal.gap_px, 0, 64);
  o.scan_subscriber_queue_size =
      param(pnh, "scan_subscriber_queue_size", o.scan_subscriber_queue_size, 1, 1000);
  o.expected_scan_rate_hz =
      param(pnh, "expected_scan_rate_hz", o.expected_scan_rate_hz, 0.01, 1000.0);
  o.min_accepted_share = param(pnh, "min_accepted_share", o.min_accepted_share, 0.0, 1.0);
  return o;
}

LocalizerPipelineOptions pipelineOptions(const MatcherOptions& m, const EkfNodeOptions& e) {
  LocalizerPipelineOptions o;
  o.ekf = e.ekf;
  o.filter = e.filter;
  o.registration = m.registration;
  o.policy = m.policy;
  o.method = m.method;
  o.session = m.session;
  return o;
}

WindowExtent configuredPoseWindow(const MatcherOptions& m) {
  return WindowExtent{m.initial_pose_half_xy_m, m.initial_pose_half_xy_m,
                      m.initial_pose_half_heading_rad};
}

}  // namespace node
}  // namespace gmm_localization
