#pragma once
// What the EKF tells its caller: the outcome of each measurement and running counters.

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "gmm_localization/core/filter/ekf_measurement.h"

namespace gmm_localization {

/// Outcome of offering one measurement to the filter.
enum class FuseOutcome {
  kFused,                   ///< entered the state
  kRejectedGate,            ///< Mahalanobis distance beyond the gate (see FuseReport)
  kRejectedInvalid,         ///< non-finite value, bad covariance, disabled or empty selection
  kRejectedTooOld,          ///< older than the history (or than the last reset)
  kRejectedNotInitialized,  ///< no reset() yet
  kRejectedNumerical,       ///< innovation covariance not positive definite, or the update
                            ///< would have produced a non-finite state; state left unchanged
  kTimeWentBackwards,       ///< a run of stale_reset_count stale stamps, or one more than
                            ///< time_backwards_reset_s before the filter time: the caller
                            ///< should reset()
  kTimeJumpedForward,       ///< stamp later than the filter time by more than
                            ///< max_prediction_gap_s: the caller should reset() after a run
  kRejectedStale,           ///< stamp earlier than the filter time by more than
                            ///< time_backwards_tolerance_s, not (yet) a run: dropped
};

/// Short name of an outcome ("fused", "rejected_gate", ...).
const char* outcomeName(FuseOutcome outcome);

struct FuseReport {
  MeasurementSource source = MeasurementSource::kPose;
  FuseOutcome outcome = FuseOutcome::kRejectedInvalid;
  double stamp_s = 0.0;
  int dimension = 0;               ///< number of fused components (0 when invalid)
  double mahalanobis_sq = NAN;     ///< d^2 = nu^T S^-1 nu, when the innovation was computed
  double gate_threshold_sq = NAN;  ///< chi-square gate on d^2 for this dimension
  int replayed = 0;                ///< later measurements re-fused because this one arrived late
  std::string reason;              ///< empty when fused

  bool fused() const { return outcome == FuseOutcome::kFused; }
  double mahalanobisDistance() const { return std::sqrt(mahalanobis_sq); }
};

/// Counters per source, counting each measurement once, on arrival (re-fusions after a delayed
/// measurement are counted in EkfDiagnostics::replayed_measurements instead).
struct SourceCounters {
  uint64_t fused = 0;
  uint64_t rejected_gate = 0;
  uint64_t rejected_invalid = 0;
  uint64_t rejected_too_old = 0;
  uint64_t rejected_stale = 0;               ///< beyond time_backwards_tolerance_s, dropped
  uint64_t rejected_other = 0;               ///< not initialized, numerical, time jumps
  uint64_t consecutive_gate_rejections = 0;  ///< reset by the next fused one of this source
  double last_mahalanobis_sq = NAN;
  double last_stamp_s = NAN;  ///< stamp of the last measurement offered
};

struct EkfDiagnostics {
  std::array<SourceCounters, kMeasurementSourceCount> sources{};
  uint64_t delayed_measurements = 0;      ///< arrived older than the newest fused stamp
  uint64_t replayed_measurements = 0;     ///< re-fusions caused by those
  uint64_t time_backwards_events = 0;     ///< kTimeWentBackwards reports
  uint64_t time_forward_jump_events = 0;  ///< kTimeJumpedForward reports (one per message)
  int consecutive_stale = 0;              ///< current run of stale messages
  uint64_t resets = 0;                    ///< reset() and setPose() calls that succeeded
  std::size_t history_entries = 0;
  double history_span_s = 0.0;  ///< newest minus oldest stored time
  /// sqrt of the largest eigenvalue of the x, y, z covariance [m] (NaN when not initialized).
  double max_position_sigma_m = NAN;
  /// sqrt of the largest eigenvalue of the x, y covariance [m].
  double max_horizontal_sigma_m = NAN;
  double yaw_sigma_rad = NAN;
  /// Estimated scale error of the INS linear twist and its sigma [-] (ekf_state.h).
  double twist_scale = NAN;
  double twist_scale_sigma = NAN;
  /// Estimated GNSS receiver bias in the map frame [m] and the sqrt of its covariance's largest
  /// eigenvalue [m] (NaN when EkfOptions::estimate_gnss_bias is off).
  Eigen::Vector2d gnss_bias_m = Eigen::Vector2d::Constant(NAN);
  double gnss_bias_sigma_m = NAN;
  /// Estimated IMU gyro bias in base_link [rad/s] and the sqrt of its covariance's largest
  /// eigenvalue (NaN when EkfOptions::estimate_gyro_bias is off).
  Eigen::Vector3d gyro_bias_radps = Eigen::Vector3d::Constant(NAN);
  double gyro_bias_sigma_radps = NAN;

  const SourceCounters& source(MeasurementSource s) const { return sources[static_cast<int>(s)]; }
};

}  // namespace gmm_localization
