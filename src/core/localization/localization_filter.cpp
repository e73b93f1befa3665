#include "gmm_localization/core/localization/localization_filter.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "gmm_localization/core/common/option_checks.h"
#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace {

template <typename M>
bool allZero(const M& m) {
  return (m.array() == 0.0).all();
}

}  // namespace

std::string MeasurementDefaults::validate() const {
  for (const std::string& e :
       {rangeProblem("defaults.imu_orientation_sigma_rad", imu_orientation_sigma_rad, 1e-6, 10.0),
        rangeProblem("defaults.imu_angular_velocity_sigma_radps", imu_angular_velocity_sigma_radps,
                     1e-6, 10.0),
        rangeProblem("defaults.imu_linear_acceleration_sigma_mps2",
                     imu_linear_acceleration_sigma_mps2, 1e-6, 100.0),
        rangeProblem("defaults.twist_linear_sigma_mps", twist_linear_sigma_mps, 1e-6, 100.0),
        rangeProblem("defaults.twist_angular_sigma_radps", twist_angular_sigma_radps, 1e-6,
                     10.0)}) {
    if (!e.empty()) return e;
  }
  return {};
}

std::string FilterPolicyOptions::validate() const {
  for (const std::string& e :
       {rangeProblem("gate_lockout_count", gate_lockout_count, 1, 1e6),
        rangeProblem("relocalize_sigma_xy_m", relocalize_sigma_xy_m, 1e-3, 1000.0),
        rangeProblem("relocalize_sigma_yaw_rad", relocalize_sigma_yaw_rad, 1e-4, 3.2),
        rangeProblem("max_start_sigma_yaw_rad", max_start_sigma_yaw_rad, 1e-4, 1e3),
        rangeProblem("lost_sigma_xy_m", lost_sigma_xy_m, 1e-3, 1e4),
        rangeProblem("lost_sigma_yaw_rad", lost_sigma_yaw_rad, 1e-4, 3.2),
        rangeProblem("unknown_z_sigma_m", unknown_z_sigma_m, 1e-3, 1000.0),
        rangeProblem("unknown_tilt_sigma_rad", unknown_tilt_sigma_rad, 1e-4, 3.2),
        rangeProblem("forward_jump_reset_count", forward_jump_reset_count, 1, 1e6),
        rangeProblem("twist_linear_min_sigma_mps", twist_linear_min_sigma_mps, 0.0, 100.0),
        rangeProblem("twist_linear_sigma_per_speed", twist_linear_sigma_per_speed, 0.0, 1.0),
        defaults.validate(), gnss.validate()}) {
    if (!e.empty()) return e;
  }
  bool any = false;
  for (bool b : match_mask) any = any || b;
  if (!any) return "match_mask selects no component";
  return {};
}

const char* filterEventName(FilterEventKind kind) {
  switch (kind) {
    case FilterEventKind::kInitializedFromPose:
      return "initialized_from_pose";
    case FilterEventKind::kInitializedFromMatch:
      return "initialized_from_match";
    case FilterEventKind::kStoppedTimeBackwards:
      return "stopped_time_backwards";
    case FilterEventKind::kStoppedTimeJump:
      return "stopped_time_jump";
    case FilterEventKind::kGateLockout:
      return "gate_lockout";
    case FilterEventKind::kRelocalizeRequest:
      return "relocalize_request";
    case FilterEventKind::kMatcherRelocalizing:
      return "matcher_relocalizing";
    case FilterEventKind::kMatcherLost:
      return "matcher_lost";
    case FilterEventKind::kStartDeferred:
      return "start_deferred";
  }
  return "?";
}

Result<LocalizationFilter> LocalizationFilter::create(const EkfOptions& ekf,
                                                      const FilterPolicyOptions& policy) {
  const std::string e = policy.validate();
  if (!e.empty()) return Result<LocalizationFilter>::failure("filter policy: " + e);
  auto filter = Ekf::create(ekf);
  if (!filter) return Result<LocalizationFilter>::failure(filter.error());
  return LocalizationFilter(std::move(filter).value(), policy);
}

void LocalizationFilter::event(FilterEventKind kind, double stamp_s, std::string detail) {
  events_.push_back(FilterEvent{kind, stamp_s, std::move(detail)});
  if (events_.size() > 100) events_.erase(events_.begin());
}

std::vector<FilterEvent> LocalizationFilter::takeEvents() {
  std::vector<FilterEvent> out;
  out.swap(events_);
  return out;
}

void LocalizationFilter::checkTime(const FuseReport& r) {
  if (r.outcome == FuseOutcome::kTimeWentBackwards) {
    stop();
    event(FilterEventKind::kStoppedTimeBackwards, r.stamp_s, r.reason);
    return;
  }
  if (r.outcome == FuseOutcome::kTimeJumpedForward) {
    if (++forward_jumps_ >= options_.forward_jump_reset_count) {
      stop();
      event(FilterEventKind::kStoppedTimeJump, r.stamp_s, r.reason);
    }
    return;
  }
  if (r.outcome != FuseOutcome::kRejectedInvalid) forward_jumps_ = 0;
}

namespace {
/// Appends to a history kept while the filter is inactive: clears it when time went backwards
/// and drops what is older than the span.
template <typename T>
void keepPending(std::deque<T>& q, const T& m, double span_s) {
  if (!q.empty() && m.stamp_s < q.back().stamp_s) q.clear();
  q.push_back(m);
  while (!q.empty() && q.front().stamp_s < m.stamp_s - span_s) q.pop_front();
}
}  // namespace

std::string LocalizationFilter::motionGapAfter(double stamp_s) const {
  // The oldest kept sample of each input that has any: the motion after stamp_s is known when
  // both reach back to it (within kMotionGapS). With no IMU or twist at all there is nothing
  // to replay and nothing missing.
  double oldest = -std::numeric_limits<double>::infinity();
  if (!pending_imu_.empty()) oldest = std::max(oldest, pending_imu_.front().stamp_s);
  if (!pending_twist_.empty()) oldest = std::max(oldest, pending_twist_.front().stamp_s);
  if (!(oldest > stamp_s + kMotionGapS)) return {};
  std::ostringstream s;
  s << "filter not started from this match: its stamp is " << oldest - stamp_s
    << " s before the oldest kept IMU/twist sample (the motion since is unknown; " << pendingSpanS()
    << " s are kept, history_length_s); waiting for a newer match";
  return s.str();
}

void LocalizationFilter::replayPending(double stamp_s) {
  std::deque<ImuMeasurement> imu;
  std::deque<TwistMeasurement> twist;
  imu.swap(pending_imu_);
  twist.swap(pending_twist_);
  while (active_ && (!imu.empty() || !twist.empty())) {
    const bool take_imu =
        !imu.empty() && (twist.empty() || imu.front().stamp_s <= twist.front().stamp_s);
    if (take_imu) {
      if (imu.front().stamp_s > stamp_s) addImu(imu.front());
      imu.pop_front();
    } else {
      if (twist.front().stamp_s > stamp_s) addTwist(twist.front());
      twist.pop_front();
    }
  }
}

std::vector<FuseReport> LocalizationFilter::addImu(ImuMeasurement imu) {
  if (!active_) {
    keepPending(pending_imu_, imu, pendingSpanS());
    return {};
  }
  const MeasurementDefaults& d = options_.defaults;
  if (allZero(imu.orientation_covariance)) {
    imu.orientation_covariance =
        Eigen::Matrix3d::Identity() * std::pow(d.imu_orientation_sigma_rad, 2);
  }
  if (allZero(imu.angular_velocity_covariance)) {
    imu.angular_velocity_covariance =
        Eigen::Matrix3d::Identity() * std::pow(d.imu_angular_velocity_sigma_radps, 2);
  }
  if (allZero(imu.linear_acceleration_covariance)) {
    imu.linear_acceleration_covariance =
        Eigen::Matrix3d::Identity() * std::pow(d.imu_linear_acceleration_sigma_mps2, 2);
  }
  std::vector<FuseReport> reports = ekf_.processImu(imu);
  for (const FuseReport& r : reports) {
    checkTime(r);
    if (!active_) break;
  }
  return reports;
}

FuseReport LocalizationFilter::addTwist(TwistMeasurement twist) {
  if (!active_) {
    keepPending(pending_twist_, twist, pendingSpanS());
    FuseReport r;
    r.source = MeasurementSource::kTwist;
    r.outcome = FuseOutcome::kRejectedNotInitialized;
    r.stamp_s = twist.stamp_s;
    r.reason = "filter not running";
    return r;
  }
  if (allZero(twist.covariance)) {
    const MeasurementDefaults& d = options_.defaults;
    twist.covariance.setZero();
    twist.covariance.diagonal() << Eigen::Vector3d::Constant(std::pow(d.twist_linear_sigma_mps, 2)),
        Eigen::Vector3d::Constant(std::pow(d.twist_angular_sigma_radps, 2));
  }
  for (int k = 0; k < 3; ++k) {  // a scale error grows with each axis' own speed
    const double floor_var =
        std::pow(options_.twist_linear_min_sigma_mps, 2) +
        std::pow(options_.twist_linear_sigma_per_speed * twist.linear_mps(k), 2);
    twist.covariance(k, k) = std::max(twist.covariance(k, k), floor_var);
  }
  const FuseReport r = ekf_.processTwist(twist);
  checkTime(r);
  return r;
}

FuseReport LocalizationFilter::addGnss(const GnssFix& fix) {
  FuseReport r;
  r.source = MeasurementSource::kGnssPosition;
  r.stamp_s = fix.stamp_s;
  if (!active_) {
    r.outcome = FuseOutcome::kRejectedNotInitialized;
    r.reason = "filter not running";
    return r;
  }
  auto m = options_.gnss_enabled
               ? gnssPositionMeasurement(georeference_, fix, options_.gnss,
                                         fromIsometry(ekf_.pose()).yaw)
               : Result<PositionMeasurement>::failure("the GNSS input is disabled (gnss/enabled)");
  if (!m) {
    ++gnss_refused_;
    r.outcome = FuseOutcome::kRejectedInvalid;
    r.reason = "GNSS fix refused: " + m.error();
    return r;
  }
  r = ekf_.processPosition(*m);
  checkTime(r);
  return r;
}

FuseReport LocalizationFilter::addMatch(double stamp_s, const Pose6& pose,
                                        const Matrix6d& covariance) {
  FuseReport r;
  r.source = MeasurementSource::kPose;
  r.stamp_s = stamp_s;
  if (!active_) {
    if (!options_.initialize_from_match) {
      r.outcome = FuseOutcome::kRejectedNotInitialized;
      r.reason = "filter not running and initialize_from_match is off";
      return r;
    }
    const std::string gap = motionGapAfter(stamp_s);
    if (!gap.empty()) {
      r.outcome = FuseOutcome::kRejectedTooOld;
      r.reason = gap;
      return r;
    }
    const Status s = ekf_.reset(toIsometry(pose), covariance, stamp_s);
    if (!s) {
      r.outcome = FuseOutcome::kRejectedInvalid;
      r.reason = s.error();
      return r;
    }
    active_ = true;
    gate_run_ = forward_jumps_ = 0;
    event(FilterEventKind::kInitializedFromMatch, stamp_s, "filter started from a scan match");
    replayPending(stamp_s);
    r.outcome = FuseOutcome::kFused;
    r.dimension = 6;
    return r;
  }
  PoseMeasurement m = PoseMeasurement::full(stamp_s, toIsometry(pose), covariance);
  m.mask = options_.match_mask;
  r = ekf_.processPose(m);
  checkTime(r);
  if (r.outcome == FuseOutcome::kFused) {
    gate_run_ = 0;
  } else if (r.outcome == FuseOutcome::kRejectedGate && active_) {
    if (++gate_run_ >= options_.gate_lockout_count) {
      std::ostringstream s;
      s << gate_run_ << " consecutive scan matches rejected by the Mahalanobis gate (last d = "
        << r.mahalanobisDistance() << "): covariance inflated";
      if (inflate(FilterEventKind::kGateLockout, stamp_s, s.str())) ++lockouts_;
    }
  }
  return r;
}

Status LocalizationFilter::inflate(FilterEventKind kind, double stamp_s, std::string detail) {
  if (!active_) return Status::failure("filter not running");
  const EkfState& s = ekf_.state();
  Matrix6d c = s.poseCovariance();
  const double vxy = options_.relocalize_sigma_xy_m * options_.relocalize_sigma_xy_m;
  const double vh = options_.relocalize_sigma_yaw_rad * options_.relocalize_sigma_yaw_rad;
  for (int i : {kStateX, kStateY, kStateYaw}) {
    const double v = std::max(c(i, i), i == kStateYaw ? vh : vxy);
    c.row(i).setZero();
    c.col(i).setZero();
    c(i, i) = v;
  }
  const Status st = ekf_.setPose(s.pose(), c, ekf_.time());
  if (!st) return st;
  gate_run_ = 0;
  event(kind, stamp_s, std::move(detail));
  return Status::success();
}

Status LocalizationFilter::relocalize(double stamp_s) {
  return inflate(FilterEventKind::kRelocalizeRequest, stamp_s,
                 "relocalization requested: covariance inflated");
}

void LocalizationFilter::onMatcherMode(double stamp_s, PriorMode mode) {
  // The mode is the newest status's; an older one (the topics' callbacks interleave) only
  // places its floor in the history.
  const bool newest = !(stamp_s < last_status_s_);
  const PriorMode before = matcher_mode_;
  if (newest) {
    last_status_s_ = stamp_s;
    matcher_mode_ = mode;
  }
  if (!active_ || (mode != PriorMode::kRelocalizing && mode != PriorMode::kLost)) return;
  const bool lost = mode == PriorMode::kLost;
  const double sxy = lost ? options_.lost_sigma_xy_m : options_.relocalize_sigma_xy_m;
  const double syaw = lost ? options_.lost_sigma_yaw_rad : options_.relocalize_sigma_yaw_rad;
  // Every status in that mode keeps the floor at its scan's stamp, in the history: a match that
  // comes late (the global search's, seconds after its scan) is fused after the floors older
  // than it and before the newer ones. The event is reported once per entry into the mode.
  const FuseReport r = ekf_.raiseCovarianceAt(stamp_s, sxy, syaw);
  if (!r.fused()) return;
  gate_run_ = 0;
  if (!newest || mode == before) return;
  std::ostringstream d;
  d << "the matcher is " << priorModeName(mode) << ": x, y, yaw sigmas raised to at least " << sxy
    << " m, " << syaw << " rad";
  event(lost ? FilterEventKind::kMatcherLost : FilterEventKind::kMatcherRelocalizing, stamp_s,
        d.str());
}

Status LocalizationFilter::setInitialPose(const Pose6& pose_in, const Matrix6d& covariance,
                                          double stamp_s, bool z_and_tilt_known) {
  Pose6 pose = pose_in;
  Matrix6d c = 0.5 * (covariance + covariance.transpose());
  if (!c.allFinite()) return Status::failure("initial pose covariance is not finite");
  const double max_yaw_var = options_.max_start_sigma_yaw_rad * options_.max_start_sigma_yaw_rad;
  if (!active_ && options_.initialize_from_match && c(kStateYaw, kStateYaw) > max_yaw_var) {
    char detail[160];
    std::snprintf(detail, sizeof detail,
                  "initial pose with a heading sigma of %.2f rad (> max_start_sigma_yaw_rad "
                  "%.2f): the first accepted match starts the filter",
                  std::sqrt(c(kStateYaw, kStateYaw)), options_.max_start_sigma_yaw_rad);
    event(FilterEventKind::kStartDeferred, stamp_s, detail);
    return Status::success();
  }
  const double vxy = options_.relocalize_sigma_xy_m * options_.relocalize_sigma_xy_m;
  const double vh = options_.relocalize_sigma_yaw_rad * options_.relocalize_sigma_yaw_rad;
  for (int i : {kStateX, kStateY, kStateYaw}) {
    if (c(i, i) < (i == kStateYaw ? vh : vxy)) {
      c.row(i).setZero();
      c.col(i).setZero();
      c(i, i) = i == kStateYaw ? vh : vxy;
    }
  }
  if (!z_and_tilt_known) {
    for (int i : {kStateZ, kStateRoll, kStatePitch}) {
      c.row(i).setZero();
      c.col(i).setZero();
    }
    if (active_) {
      const EkfState& s = ekf_.state();
      const Pose6 current = fromIsometry(s.pose());
      pose.z = current.z;
      pose.roll = current.roll;
      pose.pitch = current.pitch;
      for (int i : {kStateZ, kStateRoll, kStatePitch}) c(i, i) = s.P(i, i);
    } else {
      c(kStateZ, kStateZ) = options_.unknown_z_sigma_m * options_.unknown_z_sigma_m;
      c(kStateRoll, kStateRoll) = c(kStatePitch, kStatePitch) =
          options_.unknown_tilt_sigma_rad * options_.unknown_tilt_sigma_rad;
    }
  }
  // A pose stamped well before the filter time (a looping bag not yet noticed) restarts it.
  const bool restart =
      !active_ || stamp_s < ekf_.time() - ekf_.options().time_backwards_tolerance_s;
  const Status st = restart ? ekf_.reset(toIsometry(pose), c, stamp_s)
                            : ekf_.setPose(toIsometry(pose), c, stamp_s);
  if (!st) return st;
  active_ = true;
  gate_run_ = forward_jumps_ = 0;
  event(FilterEventKind::kInitializedFromPose, stamp_s, "initial pose");
  if (restart) replayPending(stamp_s);
  return Status::success();
}

void LocalizationFilter::stop() {
  if (active_) ++stops_;
  active_ = false;
  gate_run_ = forward_jumps_ = 0;
  matcher_mode_ = PriorMode::kNoPrior;
  last_status_s_ = -std::numeric_limits<double>::infinity();  // a new timeline
}

Result<EkfState> LocalizationFilter::stateAt(double time_s) const {
  if (!active_) return Result<EkfState>::failure("filter not running (waiting for a prior)");
  return ekf_.stateAt(time_s);
}

}  // namespace gmm_localization
