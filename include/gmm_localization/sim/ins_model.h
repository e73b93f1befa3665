#pragma once
// InsModel: an Applanix-like INS. Odometry (base_link -> odom) is dead reckoning of the true
// motion with a distance scale error s and a heading error b(t) = b0 + random walk:
//     p_odom += (1 + s) Rz(b) dp_true + position random walk,   R_odom = Rz(b) R_true,
// so that over a straight drive of length L the position drifts by s L along track and b L
// across it. White noise is added to the reported pose and twist only (it does not accumulate).
// The IMU reports orientation (odom frame, so with the heading error), angular velocity and
// specific force (acceleration minus gravity, in base_link) with constant biases and white noise.
// The odom frame coincides with the map frame at the start time.

#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/random.h"
#include "gmm_localization/sim/trajectory.h"

namespace gmm_localization {
namespace sim {

struct InsConfig {
  uint64_t seed = 21;
  double odom_rate_hz = 100.0;
  double imu_rate_hz = 200.0;
  double scale_error = 0.002;                      ///< s (fraction of distance)
  double heading_bias_rad = 0.0015;                ///< b0
  double heading_random_walk_rad_sqrt_s = 0.0002;  ///< growth of b [rad / sqrt(s)]
  double position_random_walk_m_sqrt_s = 0.005;    ///< integrated noise [m / sqrt(s)] per axis
  double position_noise_m = 0.005;                 ///< white, on the reported position
  double attitude_noise_rad = 0.0003;              ///< white, on reported roll, pitch, yaw
  double velocity_noise_mps = 0.02;                ///< white, on the reported twist
  double gyro_noise_rad_s = 0.002;
  double gyro_bias_rad_s = 0.0005;  ///< 1-sigma of the constant per-axis bias
  double accel_noise_mps2 = 0.03;
  double accel_bias_mps2 = 0.02;  ///< 1-sigma of the constant per-axis bias
  Status validate() const;
};

struct OdomSample {
  double t = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();      ///< base_link -> odom
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   ///< base_link [m/s]
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< base_link [rad/s]
  double heading_error_rad = 0.0;                              ///< b(t), for analysis
};

struct ImuSample {
  double t = 0.0;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< base_link -> odom
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();       ///< [rad/s]
  Eigen::Vector3d linear_acceleration = Eigen::Vector3d::Zero();    ///< [m/s^2], incl. gravity
};

class InsModel {
 public:
  static constexpr double kGravity = 9.80665;
  /// `trajectory` must outlive the model; samples start at t_begin.
  InsModel(const Trajectory& trajectory, const InsConfig& config, double t_begin);
  /// Appends all samples with time in [current, t_until) in time order. Call with increasing t.
  void advanceTo(double t_until, std::vector<OdomSample>* odom, std::vector<ImuSample>* imu);

 private:
  void integrate(double t);
  const Trajectory& trajectory_;
  InsConfig config_;
  Rng rng_;
  double t_ = 0.0, next_odom_ = 0.0, next_imu_ = 0.0;
  long odom_count_ = 0, imu_count_ = 0;
  double t_begin_ = 0.0;
  double heading_error_ = 0.0;
  Eigen::Vector3d gt_position_, odom_position_;
  Eigen::Vector3d gyro_bias_, accel_bias_;
};

}  // namespace sim
}  // namespace gmm_localization
