#include "gmm_localization/core/localization/match_session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "gmm_localization/core/common/option_checks.h"

namespace gmm_localization {

std::string MatchSessionOptions::validate() const {
  const auto bad = rangeProblem;
  for (const std::string& e :
       {bad("odometry_buffer_s", odometry_buffer_s, 0.1, 3600.0),
        bad("odometry_max_extrapolation_s", odometry_max_extrapolation_s, 0.0, 10.0),
        bad("deskew_twist_max_gap_s", deskew_twist_max_gap_s, 0.0, 10.0),
        bad("time_backwards_tolerance_s", time_backwards_tolerance_s, 0.0, 1e9),
        bad("max_scan_ahead_s", max_scan_ahead_s, 0.0, 1e9),
        bad("max_scan_age_s", max_scan_age_s, 0.0, 1e9),
        bad("scan_queue_size", scan_queue_size, 1, 100)}) {
    if (!e.empty()) return e;
  }
  return {};
}

std::optional<BodyTwist> deskewTwist(const ScanInput& scan, const OdometryBuffer& odometry,
                                     const PriorTracker& tracker, double max_gap_s) {
  float t_max = 0.f;
  for (float t : scan.time_s) {
    if (std::isfinite(t)) t_max = std::max(t_max, t);
  }
  const auto twist = odometry.twistAt(scan.stamp_s + 0.5 * t_max, max_gap_s);
  if (twist.ok()) return twist.value();
  if (tracker.hasPosterior() && std::abs(tracker.posterior().stamp_s - scan.stamp_s) <= max_gap_s) {
    return tracker.posterior().twist;
  }
  return std::nullopt;
}

MatchSessionState::MatchSessionState(const MatchSessionOptions& options,
                                     const LocalizationPolicyOptions& policy)
    : options_(options),
      window_policy_(policy.window),
      tracker_(policy),
      odometry_(options.odometry_buffer_s, options.odometry_max_extrapolation_s,
                options.time_backwards_tolerance_s) {}

OdometryBuffer::AddResult MatchSessionState::addOdometry(const OdometrySample& sample) {
  return odometry_.add(sample);
}

void MatchSessionState::setPosterior(const PosteriorEstimate& posterior) {
  tracker_.setPosterior(posterior);
}

void MatchSessionState::setConfiguredPose(const Pose6& pose, bool z_known,
                                          const WindowExtent* window) {
  configured_pose_ = pose;
  configured_z_known_ = z_known;
  configured_window_.reset();
  if (window != nullptr) configured_window_ = *window;
  armConfiguredPose();
}

Pose6 MatchSessionState::setInitialPose(const Pose6& pose, double stamp_s, bool z_known,
                                        bool* searched_z_known,
                                        const Eigen::Matrix3d* covariance_xyh,
                                        WindowExtent* window_out) {
  bool completed_z = z_known;
  const Pose6 full = z_known ? pose : tracker_.completePlanarPose(pose, &odometry_, &completed_z);
  const std::optional<WindowExtent> coarse =
      covariance_xyh != nullptr ? explicitPoseWindow(*covariance_xyh, window_policy_)
                                : std::nullopt;
  tracker_.setExplicitPose(full, stamp_s, PriorSource::kInitialPose, completed_z,
                           coarse ? &*coarse : nullptr);
  if (window_out != nullptr) {
    *window_out = coarse
                      ? *coarse
                      : WindowExtent{window_policy_.wide_half_xy_m, window_policy_.wide_half_xy_m,
                                     window_policy_.wide_half_heading_rad};
  }
  if (searched_z_known != nullptr) *searched_z_known = completed_z;
  return full;
}

std::string MatchSessionState::requestGlobalSearch() {
  if (tracker_.mode() == PriorMode::kNoPrior) {
    return "no pose to search around yet: give one on /initialpose (a covariance of tens of "
           "metres and an unknown heading searches the global window there)";
  }
  tracker_.requestRelocalization(/*global=*/true);
  return {};
}

MatchStart MatchSessionState::beginMatch(const ScanInput& scan, bool global_available) const {
  MatchStart s;
  s.prior = tracker_.priorAt(scan.stamp_s, &odometry_);
  if (s.prior.lost && !global_available && tracker_.lostByRejections()) {
    s.skip_reason =
        "not searched: the localization is lost and the global search of an earlier scan is "
        "running";
  } else if (s.prior.lost && !global_available) {
    // The global search of an earlier scan is running: this one is answered at the tracking
    // rate, in the interim window around the same centre.
    const WindowPolicyOptions& w = tracker_.options().window;
    s.prior.lost = false;
    s.prior.interim = true;
    s.prior.wide = true;
    s.prior.wide_window =
        WindowExtent{w.interim_half_xy_m, w.interim_half_xy_m, w.interim_half_heading_rad};
  }
  s.twist = deskewTwistFor(scan);
  s.epoch = epoch_;
  return s;
}

std::optional<BodyTwist> MatchSessionState::deskewTwistFor(const ScanInput& scan) const {
  if (!options_.deskew) return std::nullopt;
  return deskewTwist(scan, odometry_, tracker_, options_.deskew_twist_max_gap_s);
}

bool MatchSessionState::finishMatch(uint64_t epoch, MatchReport* report) {
  if (epoch != epoch_) {
    report->outcome = MatchOutcome::kSkipped;
    report->reason = "discarded: time went backwards during the match";
    report->mode_after = tracker_.mode();
    return false;
  }
  if (report->outcome == MatchOutcome::kAccepted) {
    tracker_.onAccepted(report->stamp_s, report->pose, planarCovariance(report->covariance),
                        report->prior,
                        report->has_result ? report->result.log_likelihood_per_point : NAN);
  } else if (report->outcome == MatchOutcome::kRejected) {
    tracker_.onRejected(
        report->stamp_s, report->prior,
        report->likelihood_collapsed ? Rejection::kLikelihoodCollapse : Rejection::kOther);
  }
  report->mode_after = tracker_.mode();
  return true;
}

double MatchSessionState::checkScanStamp(double stamp_s) {
  double jump = 0.0;
  if (have_last_scan_ && stamp_s < last_scan_stamp_s_ - options_.time_backwards_tolerance_s) {
    jump = last_scan_stamp_s_ - stamp_s;
    tracker_.reset();
    ++epoch_;
    ++resets_;
    // The other timeline's matches at this stamp, if remembered, else the configured pose.
    last_reset_recalled_ = tracker_.recallAt(stamp_s);
    if (last_reset_recalled_) ++recalls_;
    if (!last_reset_recalled_ && options_.configured_pose_on_reset) armConfiguredPose();
  }
  have_last_scan_ = true;
  last_scan_stamp_s_ = stamp_s;
  return jump;
}

std::string MatchSessionState::stampVersusClock(double stamp_s, double clock_s) const {
  if (!std::isfinite(stamp_s)) return "scan stamp not finite";
  if (std::isnan(clock_s)) return {};
  char reason[220];
  // Ahead of the clock and of the newest INS sample: a loaded host delivers /clock late (sim
  // time lags the data by seconds), the INS samples come with the scans.
  const double newest_data_s = odometry_.empty() ? clock_s : odometry_.newest().stamp_s;
  const double reference_s = std::max(clock_s, newest_data_s);
  if (stamp_s > reference_s + options_.max_scan_ahead_s) {
    std::snprintf(reason, sizeof(reason),
                  "scan stamped %.3f s after the clock and the newest INS sample "
                  "(max_scan_ahead_s %.1f): refused; check the driver's clock, or use_sim_time "
                  "with rosbag play --clock",
                  stamp_s - reference_s, options_.max_scan_ahead_s);
    return reason;
  }
  if (stamp_s < clock_s - options_.max_scan_age_s) {
    std::snprintf(reason, sizeof(reason),
                  "scan stamped %.3f s before the clock (max_scan_age_s %.1f): too old, refused; "
                  "check the driver's clock, or use_sim_time with rosbag play --clock",
                  clock_s - stamp_s, options_.max_scan_age_s);
    return reason;
  }
  return {};
}

void MatchSessionState::armConfiguredPose() {
  if (!configured_pose_) return;
  tracker_.setExplicitPose(*configured_pose_, NAN, PriorSource::kConfigured, configured_z_known_,
                           configured_window_ ? &*configured_window_ : nullptr);
}

}  // namespace gmm_localization
