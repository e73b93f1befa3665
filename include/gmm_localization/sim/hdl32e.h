#pragma once
// Velodyne HDL-32E: elevation table in firing order, timing, and the precomputed unit ray
// directions of one revolution in the sensor frame (x forward, y left, z up).
//
// Timing (HDL-32E manual): the 32 lasers fire one after another every 1.152 us in a 46.08 us
// cycle; at 10 Hz one revolution holds about 2170 cycles, an azimuth step of about 0.166 deg.
// The head spins clockwise seen from above, so the azimuth (counter-clockwise from +x) decreases
// with time. `firing_decimation` k > 1 simulates every k-th cycle (a coarser azimuth step)
// with the real timing of the cycles that are kept.

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace sim {

struct Hdl32eConfig {
  double rotation_rate_hz = 10.0;   ///< 5..20 Hz
  int firing_decimation = 1;        ///< keep every k-th firing cycle (1 = full rate)
  double start_azimuth_deg = 90.0;  ///< azimuth of the first firing of a revolution
  double min_range_m = 1.0;
  double max_range_m = 100.0;
  double range_noise_m = 0.02;         ///< 1-sigma Gaussian range noise
  double dropout_probability = 0.005;  ///< random missing returns on top of the power model
  double intensity_noise = 2.0;        ///< 1-sigma intensity noise [0..255 units]
  /// Return-power model: p_detect is 1/2 where rho * cos(incidence) * (ref/r)^2 equals this
  /// (calibrated so dark asphalt fades out at 40-50 m on grazing lasers).
  double detection_threshold = 0.006;
  double detection_reference_m = 60.0;
  Status validate() const;
};

class Hdl32eModel {
 public:
  static constexpr int kLasers = 32;
  static constexpr double kFiringCycleS = 46.08e-6;
  static constexpr double kLaserIntervalS = 1.152e-6;

  /// Elevation [deg] of each laser in firing order (laser id 0..31): -30.67, -9.33, -29.33, ...
  static const std::array<double, kLasers>& elevationsDeg();
  /// Ring (0 = lowest beam, 31 = highest) of a laser id.
  static int ringOfLaser(int laser);

  explicit Hdl32eModel(const Hdl32eConfig& config);

  const Hdl32eConfig& config() const { return config_; }
  double revolutionPeriod() const { return 1.0 / config_.rotation_rate_hz; }
  int firingsPerRevolution() const { return firings_; }
  /// Time between simulated firings [s] (cycle x decimation).
  double firingPeriod() const { return firing_period_; }
  double azimuthStepDeg() const;
  /// Azimuth of firing f [rad], counter-clockwise from +x.
  double azimuth(int firing) const;
  /// Unit ray direction of laser l in firing f (sensor frame).
  const Eigen::Vector3f& direction(int firing, int laser) const {
    return dirs_[firing * kLasers + laser];
  }
  /// Time of laser l in firing f relative to the revolution start [s].
  double pointTime(int firing, int laser) const {
    return firing * firing_period_ + laser * kLaserIntervalS;
  }

 private:
  Hdl32eConfig config_;
  int firings_ = 0;
  double firing_period_ = 0.0;
  std::vector<Eigen::Vector3f> dirs_;
};

}  // namespace sim
}  // namespace gmm_localization
