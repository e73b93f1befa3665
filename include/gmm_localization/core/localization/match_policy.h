#pragma once
// The localization policy (paper V-B: "scan matches initialized around our 3-sigma posterior
// belief", fused into an EKF with their uncertainty): how big a search window each scan gets,
// when a match is good enough to publish, and which 6x6 covariance is published with it.
//
// Shared, unchanged, by the matcher nodelet and by LocalizerPipeline (the offline `evaluate`
// path), so that both make the same decisions from the same options. ROS-free; no clocks.
//
// Frames and units: poses are base_link in the map frame (REP-105), SI units; covariances of
// (x, y, yaw) are [m^2, m^2, rad^2]; 6x6 covariances are in geometry_msgs order (x, y, z, roll,
// pitch, yaw).

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/matching/registration.h"

namespace gmm_localization {

/// Size of the x, y, heading search window.
struct WindowPolicyOptions {
  /// The window's half extent per axis is this many standard deviations of the prior (the
  /// paper's 3-sigma), then clamped to [min, max] below.
  double sigma_multiplier = 3.0;
  double min_half_xy_m = 1.0;            ///< [m] smallest half extent in x and in y
  double max_half_xy_m = 12.5;           ///< [m] largest (the paper's 25 m x 25 m window)
  double min_half_heading_rad = 0.0349;  ///< [rad] smallest half heading range (2 deg)
  double max_half_heading_rad = 0.2618;  ///< [rad] largest (the paper's +-15 deg)
  /// Window after an explicit pose (/initialpose, configured pose) or while relocalizing.
  double wide_half_xy_m = 12.5;           ///< [m]
  double wide_half_heading_rad = 0.2618;  ///< [rad]
  /// Height pre-alignment range used instead of RegistrationOptions::z_search_m when the
  /// prior's height is unknown (rviz "2D Pose Estimate" gives z = 0) [m].
  double unknown_z_search_m = 5.0;
  /// An explicit pose whose covariance says it is coarser than the wide window (sigma_multiplier
  /// x sigma beyond wide_half_xy_m, or a heading sigma_multiplier x sigma of 90 deg or more) is
  /// searched over that extent, up to these (a rough fix, heading unknown): global localization
  /// by the heading-interval search (global_search.h): 100 m x 100 m x 360 deg took 1.7 s
  /// median, up to 4.4 s, on one thread on the simulated town (0.8 / 2.5 s on two;
  /// docs/benchmarks.md), and far longer on real scans over a partial map.
  double global_max_half_xy_m = 50.0;         ///< [m]
  double global_max_half_heading_rad = M_PI;  ///< [rad]
  /// While lost, each global search that finds nothing (its window may not hold the vehicle:
  /// the dead-reckoned centre of a kidnapped vehicle drifts away from it at the vehicle's
  /// speed) widens the next one: half extent x this factor (1.4142: twice the area), up to
  /// global_widest_half_xy_m [m]; after the widest, global_max_half_xy_m again and so on
  /// (globalHalfExtent), since a search that stops at its node budget may have missed a vehicle
  /// inside its window as well. Back to global_max_half_xy_m when a match is accepted or a pose
  /// is given. Factor 1: never widened.
  double global_widen_factor = 1.4142;
  double global_widest_half_xy_m = 100.0;
  /// While a global search runs (in its own worker), the other scans are searched around the
  /// prior in at most this window (Prior::interim), so that they are answered at the tracking
  /// rate instead of waiting for it [m], [rad].
  double interim_half_xy_m = 2.0;
  double interim_half_heading_rad = 0.0524;

  std::string validate() const;
};

/// When a registration result is published (and offered to the EKF).
struct AcceptancePolicyOptions {
  /// Exact mean log-likelihood per refined point at the result [nats]; below it the scan is
  /// explained by the map too poorly (wrong place, heavy occlusion). Points that the map cannot
  /// explain score the raster floor (RasterOptions::ll_floor, -6 by default): a scan with half
  /// its points on snow or traffic scores about -3; a sheet the map cannot explain -6. Loose
  /// on purpose (not yet calibrated on the simulator's Snowy pass); the gate and the other
  /// rules catch wrong matches.
  double min_log_likelihood_per_point = -4.0;
  /// Share of the scan's points that lie over mapped cells at the result, in [0, 1].
  double min_map_coverage = 0.4;
  /// Largest standard deviations of the search covariance accepted: a flatter optimum is
  /// ambiguous (e.g. a featureless stretch) [m], [rad].
  double max_sigma_xy_m = 1.5;
  double max_sigma_yaw_rad = 0.05;
  /// Reject a discrete optimum on the border of the window in x, y or heading: the true
  /// optimum may lie outside it (the prior was too far off for its window).
  bool reject_on_window_edge = true;
  /// Reject a match whose search optimum is not certified (match_certificate.h: another pose
  /// of the window scores within the margin, or the proof ran out of budget). false: publish
  /// it with the uncertified covariance floors below (the EKF then weighs it little).
  bool require_certificate = false;
  /// Reject an uncertified match of a wide window (explicit pose, relocalization, stale
  /// estimate) or a global one (lost, a coarse /initialpose): a jump away from the tracked
  /// pose is taken only on a proof that nothing else in the window explains the scan as well
  /// (certificates switched off: not applied). Tracking matches follow require_certificate.
  bool require_certificate_wide = true;
  /// Likelihood collapse [nats per point]: an uncertified match of a tracking window whose
  /// log-likelihood per point lies more than this below the median of the recent accepted
  /// matches (Prior::recent_log_likelihood_per_point) is rejected. A kidnapped vehicle, or a
  /// track that slid onto a wrong pose, fits the map far worse than a moment before, and its
  /// window then holds no clear optimum; a certified match is kept (its window holds one
  /// unique explanation: a bus beside the car lowers the likelihood of a right match too).
  /// 0: off.
  double max_likelihood_drop = 1.0;
  /// Accepted matches whose median is that reference; an accepted wide or global match starts
  /// it again (from that match alone).
  int likelihood_history = 20;

  std::string validate() const;
};

/// The covariance published with an accepted match.
struct PoseCovariancePolicyOptions {
  /// true: the search-space covariance (Olson's method, MatchResult::covariance_xyh) times
  /// search_covariance_scale; false: the paper's fixed measurement uncertainties below.
  bool use_search_covariance = true;
  double search_covariance_scale = 1.0;  ///< multiplies the search covariance
  double fixed_sigma_xy_m = 0.15;        ///< [m] when use_search_covariance is false
  double fixed_sigma_yaw_rad = 0.005;    ///< [rad]
  double min_sigma_xy_m = 0.03;          ///< floors applied in both modes [m], [rad]
  /// 0.01 rad: a match's heading carries the map's own heading error (a few tenths of a degree
  /// on a surveyed map, the same from one scan to the next), which the EKF, fusing 10 matches
  /// a second as independent, must not take for a 0.1 degree measurement (config/matcher.yaml).
  double min_sigma_yaw_rad = 0.01;
  /// Standard deviations of the hill climb's z, roll and pitch (not estimated by the search):
  /// fixed [m], [rad].
  double sigma_z_m = 0.1;
  double sigma_roll_pitch_rad = 0.02;
  /// Floors of an uncertified match's x, y and yaw standard deviations [m], [rad]: a match
  /// the search cannot prove unique in its window is published (unless require_certificate)
  /// with at least these, so the EKF down-weights it. Default: the certificate's exclusion
  /// radius and heading, beyond which the search proves nothing.
  double uncertified_min_sigma_xy_m = 0.5;
  double uncertified_min_sigma_yaw_rad = 0.035;

  std::string validate() const;
};

/// Where the search centre comes from when the EKF is not usable, and when to widen.
struct RelocalizationPolicyOptions {
  /// After this many consecutive rejected matches (searches that ran but were not accepted),
  /// the matcher searches the wide window around its prior until a match is accepted.
  int max_consecutive_rejections = 5;
  /// An EKF posterior is used for a scan when its stamp is within this of the scan's [s].
  double max_posterior_age_s = 1.0;
  /// The last accepted match is used (source "previous_match") when no fresh posterior
  /// exists and it is within this age [s]; its sigma grows by previous_match_sigma_growth_mps
  /// per second of age.
  double max_previous_match_age_s = 2.0;
  double previous_match_sigma_growth_mps = 1.0;  ///< [m/s], and 0.1 rad/s on heading
  /// An older estimate (posterior or match) up to this age is still used as the centre of a
  /// wide window (e.g. after the EKF reset on a time jump); beyond it there is "no prior" [s].
  double max_stale_prior_age_s = 30.0;
  /// Accepted matches remembered by stamp for this long [s] (0: none). When time goes backwards
  /// (a looping bag, a replay restarted) and a remembered match lies within
  /// recall_max_gap_s of the new scan stamp, the search restarts around it (wide window)
  /// instead of waiting for a person or re-arming the configured pose.
  double match_history_s = 600.0;
  double recall_max_gap_s = 0.5;
  /// Lost: after this many rejected matches in a row (0: never) the search covers the global
  /// window (WindowPolicyOptions::global_max_*: by default +-50 m and the full turn) around
  /// the prior, until a match is accepted. Each such search takes seconds; scans arriving
  /// meanwhile are dropped (counted).
  int lost_after_rejections = 15;
  /// Lost sooner: after this many rejected matches of a wide window in a row (0: never). A wide
  /// window is searched around an explicit pose (configured, /initialpose) or after
  /// max_consecutive_rejections; when it fails too, the truth is likely outside it (a stale
  /// initial pose, a kidnap), and each wide search around the wrong centre takes seconds.
  int lost_after_wide_rejections = 1;
  /// Lost at once: after this many rejections in a row by the likelihood-collapse rule
  /// (AcceptancePolicyOptions::max_likelihood_drop; 0: never), the wide window is skipped: the
  /// scan fits nowhere near the estimate (a kidnap), and around a wrong centre a wide search
  /// takes seconds while the vehicle drives away from it.
  int lost_after_collapses = 5;
  /// After a jump (a match of a wide or global window accepted), an EKF posterior farther than
  /// this from the last accepted match (both carried to the scan stamp) has not fused it yet
  /// (a global match arrives seconds late) or refused it: the matches are followed instead,
  /// until a tracking match searched around the posterior is accepted [m].
  double jump_posterior_max_gap_m = 2.0;

  std::string validate() const;
};

struct LocalizationPolicyOptions {
  WindowPolicyOptions window;
  AcceptancePolicyOptions acceptance;
  PoseCovariancePolicyOptions covariance;
  RelocalizationPolicyOptions relocalization;

  /// Empty when valid, else the first offending key with its value and range.
  std::string validate() const;
};

/// Origin of a search prior (the MatchStatus prior_source strings).
enum class PriorSource { kNone, kEkf, kInitialPose, kConfigured, kPreviousMatch };
/// "none", "ekf", "initialpose", "configured", "previous_match".
const char* priorSourceName(PriorSource source);

/// Half extents of a search window [m], [m], [rad].
struct WindowExtent {
  double half_x_m = 0.0;
  double half_y_m = 0.0;
  double half_heading_rad = 0.0;
};

/// The initial guess for one scan: base_link in map at the scan stamp.
struct Prior {
  PriorSource source = PriorSource::kNone;
  Pose6 pose;
  /// Covariance of (x, y, yaw) of the prior [m^2, m^2, rad^2].
  Eigen::Matrix3d covariance_xyh = Eigen::Matrix3d::Identity();
  /// Search the wide window (explicit pose, relocalization, stale estimate).
  bool wide = false;
  /// A wide window other than WindowPolicyOptions::wide_* (a configured pose's own window);
  /// used when its half_x_m > 0.
  WindowExtent wide_window;
  /// False when the height is a guess (rviz pose): the search then pre-aligns over
  /// WindowPolicyOptions::unknown_z_search_m.
  bool z_known = true;
  /// Scan stamp minus the stamp of the estimate the prior was carried from [s].
  double age_s = 0.0;
  /// True when odometry carried the estimate to the scan stamp (else constant velocity).
  bool carried_by_odometry = false;
  /// Median log-likelihood per point of the recent accepted matches [nats] (NaN: none since
  /// the last reset), for AcceptancePolicyOptions::max_likelihood_drop.
  double recent_log_likelihood_per_point = NAN;
  /// The localization is judged lost (RelocalizationPolicyOptions::lost_after_rejections): the
  /// window is the global one.
  bool lost = false;
  /// Searched while a global search of an earlier scan runs: the window is
  /// WindowPolicyOptions::interim_half_* (in wide_window, with wide set: the certificate is
  /// required) and the likelihood collapse applies even to a certified match; not a jump when
  /// accepted (MatchSessionState::beginMatch with global_available false).
  bool interim = false;
  /// Which explicit pose (PriorTracker::setExplicitPose call, counted from 1) this prior came
  /// from; 0 for other sources. Lets a match that started before a newer explicit pose leave
  /// that pose pending.
  uint64_t explicit_generation = 0;

  bool valid() const { return source != PriorSource::kNone; }
};

/// Wide window for a wide prior (its own wide_window when set); otherwise sigma_multiplier x the
/// prior's standard deviation per axis (x, y in the map frame; yaw), each clamped to [min, max].
/// Non-finite sigmas give the maximum.
WindowExtent searchWindowFor(const Prior& prior, const WindowPolicyOptions& options);

/// The half extent [m] of a lost matcher's global window after `misses` global searches that
/// found nothing: global_max_half_xy_m x global_widen_factor^k, capped at
/// global_widest_half_xy_m, where k = misses modulo the number of sizes in that cycle.
double globalHalfExtent(const WindowPolicyOptions& options, int misses);

/// The window for an explicit pose with (x, y, yaw) covariance `covariance_xyh`: the wide
/// window (nullopt) unless sigma_multiplier x sigma exceeds wide_half_xy_m (then that extent,
/// capped by global_max_half_xy_m) or the heading is unknown (then global_max_half_heading_rad).
/// Non-finite or negative variances: the wide window.
std::optional<WindowExtent> explicitPoseWindow(const Eigen::Matrix3d& covariance_xyh,
                                               const WindowPolicyOptions& options);

/// The discretised window Registration::match will search for this request and map
/// resolution (cells and heading steps), for edge checks and the traversal picture.
SearchWindow discreteWindow(const MatchRequest& request, double heading_step_rad,
                            double resolution_m);

struct AcceptanceDecision {
  bool accepted = false;
  std::string reason;  ///< why not, naming the value and the limit; empty when accepted
  bool likelihood_collapsed = false;  ///< rejected by AcceptancePolicyOptions::max_likelihood_drop
};

/// Applies the acceptance rules in the order: finite result, map coverage, log-likelihood per
/// point, search covariance, window edge, certificate (when required; `wide`: the prior was
/// wide or lost, see require_certificate_wide), likelihood collapse (tracking windows, and
/// interim ones whatever their certificate; recent_log_likelihood_per_point: the reference,
/// NaN: none yet). `window` is discreteWindow() of the request.
AcceptanceDecision acceptMatch(const MatchResult& result, const SearchWindow& window,
                               const AcceptancePolicyOptions& options, bool wide = false,
                               double recent_log_likelihood_per_point = NAN, bool interim = false);

/// The 6x6 covariance published with a match: the (x, y, yaw) block from the search
/// covariance (scaled) or the fixed sigmas, floored; z, roll, pitch from the fixed sigmas; no
/// correlation between the two groups. Always symmetric positive definite and finite when the
/// options are valid (a non-finite search covariance falls back to the fixed sigmas).
/// `certified` false raises the x, y, yaw floors to the uncertified_min_* sigmas.
Matrix6d publishedPoseCovariance(const Eigen::Matrix3d& search_covariance_xyh,
                                 const PoseCovariancePolicyOptions& options, bool certified = true);

}  // namespace gmm_localization
