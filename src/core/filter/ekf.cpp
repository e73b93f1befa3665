#include "gmm_localization/core/filter/ekf.h"

#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "gmm_localization/core/filter/ekf_gating.h"
#include "gmm_localization/core/filter/ekf_process_model.h"
#include "gmm_localization/core/filter/ekf_update.h"

namespace gmm_localization {
namespace {

FuseReport rejection(MeasurementSource source, double stamp_s, FuseOutcome outcome,
                     std::string reason) {
  FuseReport r;
  r.source = source;
  r.stamp_s = stamp_s;
  r.outcome = outcome;
  r.reason = std::move(reason);
  return r;
}

std::string timeReason(const char* what, double stamp_s, double filter_time_s, double limit_s,
                       const char* key) {
  std::ostringstream s;
  s.precision(15);
  s << "stamp " << stamp_s << " s is " << what << " the filter time " << filter_time_s << " s by "
    << std::abs(filter_time_s - stamp_s) << " s (" << key << " = " << limit_s << ")";
  return s.str();
}

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

template <typename Matrix>
double largestSigma(const Matrix& c) {
  Eigen::SelfAdjointEigenSolver<Matrix> es;
  es.computeDirect(c, Eigen::EigenvaluesOnly);  // closed form for 2x2 and 3x3
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

}  // namespace

Result<Ekf> Ekf::create(const EkfOptions& options) {
  const Status valid = options.validate();
  if (!valid) return Result<Ekf>::failure(valid.error());
  return Ekf(options);
}

Ekf::Ekf(const EkfOptions& options) : options_(options) {
  for (int s = 0; s < kMeasurementSourceCount; ++s) {
    const auto source = static_cast<MeasurementSource>(s);
    const double p = source == MeasurementSource::kPose           ? options_.pose_gate_probability
                     : source == MeasurementSource::kTwist        ? options_.twist_gate_probability
                     : source == MeasurementSource::kGnssPosition ? options_.gnss_gate_probability
                                                                  : options_.imu_gate_probability;
    gate_sq_[s][0] = 0.0;
    for (int dof = 1; dof <= kMaxMeasurementSize; ++dof) {
      gate_sq_[s][dof] = chiSquareQuantile(p, dof);
    }
  }
}

double Ekf::gateThresholdSq(MeasurementSource source, int dimension) const {
  return gate_sq_[static_cast<int>(source)][dimension];
}

Result<EkfState> Ekf::validatedPoseState(const Eigen::Isometry3d& map_T_base,
                                         const Matrix6d& pose_covariance, double time_s,
                                         const char* caller) const {
  const auto m =
      makePoseMeasurement(PoseMeasurement::full(time_s, map_T_base, pose_covariance), options_);
  if (!m) return Result<EkfState>::failure(std::string(caller) + ": " + m.error());
  EkfState s;
  s.time_s = time_s;
  s.x.setZero();
  setPoseInState(map_T_base, &s.x);
  s.P = StateCovariance::Zero();
  for (int i = 0; i < kTunedStateCount; ++i) s.P(i, i) = options_.initial_variance[i];
  // The GNSS bias starts at 0 with its stationary variance (a receiver on for a while).
  const double bias_var = options_.gnss_bias_sigma_m * options_.gnss_bias_sigma_m;
  s.P(kStateGnssBiasX, kStateGnssBiasX) = bias_var;
  s.P(kStateGnssBiasY, kStateGnssBiasY) = bias_var;
  const double gyro_var = options_.gyro_bias_sigma_radps * options_.gyro_bias_sigma_radps;
  for (int i = kStateGyroBiasX; i <= kStateGyroBiasZ; ++i) s.P(i, i) = gyro_var;
  s.P.topLeftCorner<6, 6>() = m->R;  // symmetrised, floored
  return s;
}

Status Ekf::reset(const Eigen::Isometry3d& map_T_base, const Matrix6d& pose_covariance,
                  double time_s) {
  const auto s = validatedPoseState(map_T_base, pose_covariance, time_s, "reset");
  if (!s) return Status::failure(s.error());
  history_.clear(*s);
  initialized_ = true;
  ++diagnostics_.resets;
  diagnostics_.consecutive_stale = 0;  // a new time line
  // A new pose starts a new gating history: rejections in a row refer to the old estimate.
  for (SourceCounters& c : diagnostics_.sources) c.consecutive_gate_rejections = 0;
  return Status::success();
}

Status Ekf::setPose(const Eigen::Isometry3d& map_T_base, const Matrix6d& pose_covariance,
                    double time_s) {
  const EkfState& latest = history_.latest();
  if (!initialized_ || !(time_s - latest.time_s <= options_.max_prediction_gap_s)) {
    return reset(map_T_base, pose_covariance, time_s);
  }
  const auto pose = validatedPoseState(map_T_base, pose_covariance, time_s, "setPose");
  if (!pose) return Status::failure(pose.error());
  EkfState s = latest;
  predictState(&s, std::max(time_s, latest.time_s), options_.process_noise_density,
               options_.max_prediction_step_s, calibrationProcess());
  s.x.head<6>() = pose->x.head<6>();
  s.P.topRows<6>().setZero();
  s.P.leftCols<6>().setZero();
  s.P.topLeftCorner<6, 6>() = pose->P.topLeftCorner<6, 6>();
  history_.clear(s);
  ++diagnostics_.resets;
  diagnostics_.consecutive_stale = 0;
  for (SourceCounters& c : diagnostics_.sources) c.consecutive_gate_rejections = 0;
  return Status::success();
}

CalibrationProcess Ekf::calibrationProcess() const {
  CalibrationProcess c;
  if (options_.estimate_gnss_bias) {
    c.gnss_bias_sigma_m = options_.gnss_bias_sigma_m;
    c.gnss_bias_tau_s = options_.gnss_bias_tau_s;
  }
  if (options_.estimate_gyro_bias) c.gyro_bias_density = options_.gyro_bias_random_walk;
  return c;
}

double Ekf::time() const {
  return initialized_ ? history_.latest().time_s : std::numeric_limits<double>::quiet_NaN();
}

std::vector<FuseReport> Ekf::processImu(const ImuMeasurement& imu) {
  std::vector<FuseReport> reports;
  const bool orientation = imu.has_orientation && options_.imu_use_orientation;
  const bool rates = imu.has_angular_velocity && options_.imu_use_angular_velocity;
  const bool acceleration = imu.has_linear_acceleration && options_.imu_use_linear_acceleration;
  if (!orientation && !rates && !acceleration) return reports;
  // The parts share the message's stamp: judge it once, so that one message stamped far ahead
  // (or stale) is one forward jump (or one stale drop) for the caller's counters, not three.
  if (initialized_ && std::isfinite(imu.stamp_s)) {
    const MeasurementSource first = orientation ? MeasurementSource::kImuOrientation
                                    : rates     ? MeasurementSource::kImuAngularVelocity
                                                : MeasurementSource::kImuLinearAcceleration;
    if (std::optional<FuseReport> rejected = checkStamp(first, imu.stamp_s)) {
      count(*rejected);
      reports.push_back(std::move(*rejected));
      return reports;
    }
  }
  if (orientation) {
    reports.push_back(process(makeImuOrientationMeasurement(imu, options_),
                              MeasurementSource::kImuOrientation, imu.stamp_s));
  }
  if (rates) {
    reports.push_back(process(makeImuAngularVelocityMeasurement(imu, options_),
                              MeasurementSource::kImuAngularVelocity, imu.stamp_s));
  }
  if (acceleration) {
    reports.push_back(process(makeImuAccelerationMeasurement(imu, options_),
                              MeasurementSource::kImuLinearAcceleration, imu.stamp_s));
  }
  return reports;
}

FuseReport Ekf::processTwist(const TwistMeasurement& twist) {
  return process(makeTwistMeasurement(twist, options_), MeasurementSource::kTwist, twist.stamp_s);
}

FuseReport Ekf::processPose(const PoseMeasurement& pose) {
  return process(makePoseMeasurement(pose, options_), MeasurementSource::kPose, pose.stamp_s);
}

FuseReport Ekf::processPosition(const PositionMeasurement& position) {
  return process(makePositionMeasurement(position, options_), MeasurementSource::kGnssPosition,
                 position.stamp_s);
}

FuseReport Ekf::raiseCovarianceAt(double stamp_s, double sigma_xy_m, double sigma_yaw_rad) {
  EkfMeasurement m;
  m.source = MeasurementSource::kCovarianceFloor;
  m.model = MeasurementModel::kCovarianceFloor;
  m.stamp_s = stamp_s;
  m.size = 3;
  m.indices = {kStateX, kStateY, kStateYaw, 0, 0, 0};
  m.z = MeasurementVector(3);
  m.z << sigma_xy_m * sigma_xy_m, sigma_xy_m * sigma_xy_m, sigma_yaw_rad * sigma_yaw_rad;
  m.R = MeasurementCovariance::Identity(3, 3);
  Result<EkfMeasurement> r(std::move(m));
  if (!std::isfinite(stamp_s) || !(sigma_xy_m >= 0.0) || !(sigma_yaw_rad >= 0.0) ||
      !std::isfinite(sigma_xy_m) || !std::isfinite(sigma_yaw_rad)) {
    r = Result<EkfMeasurement>::failure("covariance floor: stamp and sigmas must be finite, >= 0");
  }
  return process(r, MeasurementSource::kCovarianceFloor, stamp_s);
}

std::optional<FuseReport> Ekf::checkStamp(MeasurementSource source, double stamp_s) {
  const double latest = history_.latest().time_s;
  const double behind = latest - stamp_s;
  if (behind > options_.time_backwards_tolerance_s) {
    // Stale. One such message is a glitch (a late driver buffer, a bad stamp) and is dropped;
    // a run of them, or one older than any sensor delay, is a clock that went back.
    int& run = diagnostics_.consecutive_stale;
    ++run;
    std::string reason = timeReason("before", stamp_s, latest, options_.time_backwards_tolerance_s,
                                    "time_backwards_tolerance_s");
    if (behind > options_.time_backwards_reset_s || run >= options_.stale_reset_count) {
      ++diagnostics_.time_backwards_events;
      reason +=
          behind > options_.time_backwards_reset_s
              ? ", more than time_backwards_reset_s = " + number(options_.time_backwards_reset_s) +
                    " s"
              : ", " + std::to_string(run) + " stale messages in a row (stale_reset_count)";
      return rejection(source, stamp_s, FuseOutcome::kTimeWentBackwards,
                       reason + ": time went backwards; reset the filter");
    }
    return rejection(source, stamp_s, FuseOutcome::kRejectedStale,
                     reason + ": stale message dropped (" + std::to_string(run) + " in a row; " +
                         std::to_string(options_.stale_reset_count) +
                         " in a row mean time went backwards)");
  }
  diagnostics_.consecutive_stale = 0;  // a message within the tolerance ends a stale run
  if (stamp_s < latest - options_.history_length_s || stamp_s < history_.base().time_s) {
    return rejection(
        source, stamp_s, FuseOutcome::kRejectedTooOld,
        timeReason("before", stamp_s, latest, options_.history_length_s, "history_length_s") +
            ", or before the oldest stored state / last reset");
  }
  if (stamp_s - latest > options_.max_prediction_gap_s) {
    ++diagnostics_.time_forward_jump_events;
    return rejection(source, stamp_s, FuseOutcome::kTimeJumpedForward,
                     timeReason("after", stamp_s, latest, options_.max_prediction_gap_s,
                                "max_prediction_gap_s") +
                         "; reset the filter after a run of them");
  }
  return std::nullopt;
}

FuseReport Ekf::process(const Result<EkfMeasurement>& m, MeasurementSource source, double stamp_s) {
  FuseReport report;
  const double latest = history_.latest().time_s;
  std::optional<FuseReport> out_of_time;
  if (!m) {
    report = rejection(source, stamp_s, FuseOutcome::kRejectedInvalid, m.error());
  } else if (!initialized_) {
    report = rejection(source, stamp_s, FuseOutcome::kRejectedNotInitialized,
                       "filter not initialized: call reset() first");
  } else if ((out_of_time = checkStamp(source, stamp_s))) {
    report = std::move(*out_of_time);
  } else if (stamp_s >= latest) {
    report = fuseAfter(*m, history_.latest());
  } else {
    // Late: rewind to the last state at or before the stamp, insert, re-fuse the rest in order
    // (their outcomes may change; arrival counters keep the first outcome).
    ++diagnostics_.delayed_measurements;
    std::vector<HistoryEntry> later = history_.rewindTo(stamp_s);
    report = fuseAfter(*m, history_.latest());
    for (const HistoryEntry& e : later) fuseAfter(e.measurement, history_.latest());
    report.replayed = static_cast<int>(later.size());
    diagnostics_.replayed_measurements += later.size();
  }
  if (initialized_) {
    history_.trim(history_.latest().time_s - options_.history_length_s,
                  static_cast<std::size_t>(options_.max_history_entries));
  }
  count(report);
  return report;
}

FuseReport Ekf::fuseAfter(const EkfMeasurement& m, const EkfState& from) {
  EkfState s = from;
  predictState(&s, m.stamp_s, options_.process_noise_density, options_.max_prediction_step_s,
               calibrationProcess());
  FuseReport report;
  report.source = m.source;
  report.stamp_s = m.stamp_s;
  report.dimension = m.size;
  report.gate_threshold_sq = gateThresholdSq(m.source, m.size);
  const UpdateResult u = applyMeasurement(m, report.gate_threshold_sq, options_.gravity_mps2, &s);
  report.mahalanobis_sq = u.mahalanobis_sq;
  report.reason = u.reason;
  switch (u.kind) {
    case UpdateResult::Kind::kFused:
      report.outcome = FuseOutcome::kFused;
      break;
    case UpdateResult::Kind::kRejectedGate:
      report.outcome = FuseOutcome::kRejectedGate;
      break;
    case UpdateResult::Kind::kRejectedNumerical:
      report.outcome = FuseOutcome::kRejectedNumerical;
      break;
  }
  history_.append(HistoryEntry{m, s, report.fused()});
  return report;
}

void Ekf::count(const FuseReport& r) {
  SourceCounters& c = diagnostics_.sources[static_cast<int>(r.source)];
  c.last_stamp_s = r.stamp_s;
  if (std::isfinite(r.mahalanobis_sq)) c.last_mahalanobis_sq = r.mahalanobis_sq;
  switch (r.outcome) {
    case FuseOutcome::kFused:
      ++c.fused;
      c.consecutive_gate_rejections = 0;
      break;
    case FuseOutcome::kRejectedGate:
      ++c.rejected_gate;
      ++c.consecutive_gate_rejections;
      break;
    case FuseOutcome::kRejectedInvalid:
      ++c.rejected_invalid;
      break;
    case FuseOutcome::kRejectedTooOld:
      ++c.rejected_too_old;
      break;
    case FuseOutcome::kRejectedStale:
      ++c.rejected_stale;
      break;
    default:
      ++c.rejected_other;
      break;
  }
}

Result<EkfState> Ekf::stateAt(double time_s) const {
  if (!initialized_) return Result<EkfState>::failure("stateAt: filter not initialized");
  if (!std::isfinite(time_s)) return Result<EkfState>::failure("stateAt: time is not finite");
  const EkfState& latest = history_.latest();
  if (time_s - latest.time_s > options_.max_prediction_gap_s) {
    return Result<EkfState>::failure("stateAt: " + timeReason("after", time_s, latest.time_s,
                                                              options_.max_prediction_gap_s,
                                                              "max_prediction_gap_s"));
  }
  const EkfState* from = time_s >= latest.time_s ? &latest : history_.stateAtOrBefore(time_s);
  if (from == nullptr) {
    return Result<EkfState>::failure(
        "stateAt: " +
        timeReason("before", time_s, latest.time_s, options_.history_length_s, "history_length_s") +
        ", older than the stored history");
  }
  EkfState s = *from;
  predictState(&s, time_s, options_.process_noise_density, options_.max_prediction_step_s,
               calibrationProcess());
  return s;
}

EkfDiagnostics Ekf::diagnostics() const {
  EkfDiagnostics d = diagnostics_;
  d.history_entries = history_.size();
  if (!initialized_) return d;
  const EkfState& s = history_.latest();
  d.history_span_s = s.time_s - history_.base().time_s;
  const Eigen::Matrix3d position = s.P.topLeftCorner<3, 3>();
  d.max_position_sigma_m = largestSigma(position);
  d.max_horizontal_sigma_m = largestSigma(Eigen::Matrix2d(position.topLeftCorner<2, 2>()));
  d.yaw_sigma_rad = std::sqrt(s.P(kStateYaw, kStateYaw));
  d.twist_scale = s.twistScale();
  d.twist_scale_sigma = std::sqrt(s.P(kStateTwistScale, kStateTwistScale));
  if (options_.estimate_gnss_bias) {
    d.gnss_bias_m = s.gnssBias();
    d.gnss_bias_sigma_m =
        largestSigma(Eigen::Matrix2d(s.P.block<2, 2>(kStateGnssBiasX, kStateGnssBiasX)));
  }
  if (options_.estimate_gyro_bias) {
    d.gyro_bias_radps = s.gyroBias();
    d.gyro_bias_sigma_radps =
        largestSigma(Eigen::Matrix3d(s.P.block<3, 3>(kStateGyroBiasX, kStateGyroBiasX)));
  }
  return d;
}

}  // namespace gmm_localization
