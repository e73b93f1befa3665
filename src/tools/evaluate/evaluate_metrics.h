#pragma once
// The evaluation maths of `evaluate` (paper section V), ROS-free and unit-tested
// (test/tools/evaluate/evaluate_metrics_test.cpp):
//  - time association: a ground-truth trajectory interpolated at an estimate's stamp;
//  - lateral / longitudinal error: the planar position error expressed in the heading frame
//    of the ground-truth vehicle (paper Fig. 10, Table I);
//  - RMS and percentiles of an error series;
//  - obstacle classification counts with precision and recall (paper V-C, Fig. 11).
//
// Frames and units: map frame, metres, radians, seconds.

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace eval {

/// A planar pose (with height) at a time.
struct PoseStamped2 {
  double t = 0.0;  ///< [s]
  double x = 0.0, y = 0.0, z = 0.0;
  double yaw = 0.0;                ///< [rad]
  double roll = 0.0, pitch = 0.0;  ///< [rad] (for priors; not part of the error)
};

/// A ground-truth trajectory, samples in time order.
class Trajectory {
 public:
  /// Appends a sample; ignored (returns false) when not newer than the last one.
  bool add(const PoseStamped2& p);
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  const std::vector<PoseStamped2>& samples() const { return samples_; }
  double startTime() const { return samples_.front().t; }
  double endTime() const { return samples_.back().t; }

  /// The pose at t: linear in x, y, z and along the shorter arc in each angle between the samples
  /// around t. None when t is outside [start, end] or the bracketing samples are more than
  /// max_gap_s apart (a gap in the ground truth is not bridged).
  std::optional<PoseStamped2> at(double t, double max_gap_s) const;

 private:
  std::vector<PoseStamped2> samples_;
};

/// The same pose as a Pose6 (core/common/types.h), and back with a stamp.
Pose6 toPose6(const PoseStamped2& p);
PoseStamped2 planar(const Pose6& p, double t);

/// Angle wrapped to (-pi, pi].
double wrapAngle(double a);

/// Position error of an estimate in the vehicle's heading frame (truth's yaw): longitudinal
/// along the heading (positive: estimate ahead), lateral across it (positive: estimate to the
/// left), and the heading error (estimate - truth, wrapped).
struct VehicleFrameError {
  double longitudinal_m = 0.0;
  double lateral_m = 0.0;
  double yaw_rad = 0.0;
  double planar_m() const;  ///< hypot(longitudinal, lateral)
};
VehicleFrameError vehicleFrameError(const PoseStamped2& estimate, const PoseStamped2& truth);

/// Root mean square; NaN for an empty series (no data is no data, not 0 m).
double rms(const std::vector<double>& v);
/// Mean of |v|; NaN for an empty series.
double meanAbs(const std::vector<double>& v);
/// The q-quantile (q in [0, 1]) of v by linear interpolation between order statistics; NaN for
/// an empty series.
double quantile(std::vector<double> v, double q);

/// Summary of a lateral / longitudinal error series.
struct ErrorSummary {
  size_t count = 0;
  double rms_longitudinal_m = 0.0, rms_lateral_m = 0.0, rms_yaw_rad = 0.0;
  double mean_abs_longitudinal_m = 0.0, mean_abs_lateral_m = 0.0;
  /// NaN without errors (no data is reported as none, not as 0 cm).
  double p95_planar_m = std::numeric_limits<double>::quiet_NaN();
  double max_planar_m = std::numeric_limits<double>::quiet_NaN();
};
ErrorSummary summarize(const std::vector<VehicleFrameError>& errors);

/// Binary classification counts (positive = obstacle).
struct Confusion {
  uint64_t tp = 0, fp = 0, fn = 0, tn = 0;
  void add(bool predicted, bool actual);
  Confusion& operator+=(const Confusion& o);
  /// tp / (tp + fp); NaN when nothing was predicted positive.
  double precision() const;
  /// tp / (tp + fn); NaN when nothing is actually positive.
  double recall() const;
  uint64_t total() const { return tp + fp + fn + tn; }
};

/// Random planar offsets for the registration experiment (paper Fig. 8): uniform over the disc
/// of radius radius_m and over +-max_heading_rad, from a seeded generator (see .cpp).
struct PlanarOffset {
  double dx_m = 0.0, dy_m = 0.0, dyaw_rad = 0.0;
  double distance_m() const;
};
class OffsetSampler {
 public:
  OffsetSampler(uint64_t seed, double radius_m, double max_heading_rad);
  PlanarOffset next();

 private:
  uint64_t state_;
  double radius_m_, max_heading_rad_;
  double uniform();  ///< [0, 1)
};

}  // namespace eval
}  // namespace gmm_localization
