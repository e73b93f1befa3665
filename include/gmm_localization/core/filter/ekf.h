#pragma once
// The localization EKF (paper section V-B: "the only measurements used were those from our IMU
// for odometry and our multiresolution scan matches"), ROS-free. The ekf nodelet owns one Ekf,
// feeds it IMU, INS twist and scan-match poses, and publishes state() / stateAt(now).
//
// Contract:
// - Frames and units: ekf_state.h (base_link in map, SI units); inputs: ekf_measurement.h.
// - Time is the caller's, in seconds (ROS stamps converted with toSec()); the filter reads no
//   clock. Its time is the newest stamp it has fused (or reset to).
// - Measurements may arrive late: a stamp older than the filter time but within
//   EkfOptions::history_length_s is inserted in stamp order and the later measurements re-fused,
//   giving the same result (to rounding) as in-order delivery. Older ones are rejected
//   (kRejectedTooOld). A stamp older than time_backwards_tolerance_s is stale: dropped
//   (kRejectedStale) unless it ends a run of stale_reset_count stale messages or is older than
//   time_backwards_reset_s, which report kTimeWentBackwards (a looping bag) and the caller
//   should reset(); stamps too far ahead report kTimeJumpedForward. Time is judged once per
//   message: an IMU message stamped out of time gives one report, not one per part.
// - Every input is validated; an invalid one is rejected with a reason and never touches the
//   state. A valid measurement rejected by the Mahalanobis gate (or as numerically unusable)
//   still advances the filter time to its stamp (the prediction is kept) and stays in the
//   history, so a replay after a late measurement re-evaluates it.
// - The covariance stays symmetric with a positive diagonal (Joseph-form updates, symmetrised
//   predictions). No method throws or logs.
// - Not thread-safe: one caller thread (the nodelet serialises its callbacks) or a lock.

#include <array>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/filter/ekf_diagnostics.h"
#include "gmm_localization/core/filter/ekf_history.h"
#include "gmm_localization/core/filter/ekf_measurement.h"
#include "gmm_localization/core/filter/ekf_options.h"
#include "gmm_localization/core/filter/ekf_process_model.h"
#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {

class Ekf {
 public:
  /// A filter with validated options, not yet initialized; fails with options.validate()'s
  /// reason.
  static Result<Ekf> create(const EkfOptions& options);

  const EkfOptions& options() const { return options_; }

  /// (Re)starts the filter at time_s with pose map_T_base and its 6x6 covariance (x, y, z,
  /// roll, pitch, yaw); velocities, rates, accelerations and the twist scale start at zero with
  /// EkfOptions::initial_variance. Clears the history; any time_s is accepted (also earlier
  /// than the filter time: this is how a looping bag recovers). Fails, changing nothing, on a
  /// non-finite or non-rotation pose or a covariance that is not symmetric positive definite.
  Status reset(const Eigen::Isometry3d& map_T_base, const Matrix6d& pose_covariance, double time_s);

  /// Replaces the pose (from /initialpose or a relocalization) and its covariance, keeping the
  /// velocity, rate, acceleration and twist-scale estimates; cross-covariances of the pose are
  /// zeroed. Applies at max(time_s, time()) after predicting there; clears the history (older
  /// measurements are then too old). Behaves as reset() when not initialized, or when time_s is
  /// beyond max_prediction_gap_s ahead. Same failures as reset().
  Status setPose(const Eigen::Isometry3d& map_T_base, const Matrix6d& pose_covariance,
                 double time_s);

  bool initialized() const { return initialized_; }

  /// Fuses the used parts of an IMU sample in the order orientation, angular velocity,
  /// acceleration (so gravity removal sees the updated roll/pitch): one report per part that is
  /// present and enabled; empty when there is none. A message whose stamp is out of time
  /// (stale, backwards, too far ahead) gives one report for the whole message (its first part's
  /// source), so callers counting time jumps count messages.
  std::vector<FuseReport> processImu(const ImuMeasurement& imu);
  /// Fuses an odometry body twist (its linear part as (1 + s) v with the estimated scale error
  /// s when EkfOptions::estimate_twist_scale, see ekf_state.h).
  FuseReport processTwist(const TwistMeasurement& twist);
  /// Fuses an absolute pose in map (scan match), gated with pose_gate_probability.
  FuseReport processPose(const PoseMeasurement& pose);
  /// Fuses an absolute position in map (a GNSS fix), gated with gnss_gate_probability; counted
  /// under MeasurementSource::kGnssPosition.
  FuseReport processPosition(const PositionMeasurement& position);
  /// Raises the x, y variances to at least sigma_xy_m^2 and the yaw variance to sigma_yaw_rad^2
  /// at stamp_s (MeasurementModel::kCovarianceFloor), in the history like a measurement: a
  /// pose stamped later, even one that arrives late, is fused after it.
  FuseReport raiseCovarianceAt(double stamp_s, double sigma_xy_m, double sigma_yaw_rad);

  /// Filter time [s]: newest stamp fused or reset to; NaN before initialization.
  double time() const;
  /// Newest state (mean, covariance, time). Only meaningful when initialized().
  const EkfState& state() const { return history_.latest(); }
  /// Pose of base_link in map at the newest state.
  Eigen::Isometry3d pose() const { return state().pose(); }

  /// The state at time_s without changing the filter: predicted forward from the newest state,
  /// or, for a time within the history, from the last stored state before it. Fails when not
  /// initialized, time_s is not finite, older than the history, or more than
  /// max_prediction_gap_s ahead of the filter time.
  Result<EkfState> stateAt(double time_s) const;

  /// Counters and the current uncertainty summary.
  EkfDiagnostics diagnostics() const;

 private:
  explicit Ekf(const EkfOptions& options);

  // Time checks, insertion (with replay when late), counting.
  FuseReport process(const Result<EkfMeasurement>& m, MeasurementSource source, double stamp_s);
  // The time rules for one message at stamp_s (initialized filter): a rejection report, or
  // nothing when the stamp may be fused. Keeps the run of stale messages.
  std::optional<FuseReport> checkStamp(MeasurementSource source, double stamp_s);
  // Predicts a copy of `from` to m's stamp, updates it, appends the entry; returns the report.
  FuseReport fuseAfter(const EkfMeasurement& m, const EkfState& from);
  double gateThresholdSq(MeasurementSource source, int dimension) const;
  // The calibration states' processes (held when not estimated).
  CalibrationProcess calibrationProcess() const;
  void count(const FuseReport& report);
  Result<EkfState> validatedPoseState(const Eigen::Isometry3d& map_T_base,
                                      const Matrix6d& pose_covariance, double time_s,
                                      const char* caller) const;

  EkfOptions options_;
  bool initialized_ = false;
  EkfHistory history_;
  /// Chi-square gate on d^2 per source and dimension (index 1..kMaxMeasurementSize).
  std::array<std::array<double, kMaxMeasurementSize + 1>, kMeasurementSourceCount> gate_sq_{};
  EkfDiagnostics diagnostics_;
};

}  // namespace gmm_localization
