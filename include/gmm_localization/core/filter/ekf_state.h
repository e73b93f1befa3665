#pragma once
// EKF state layout, frames and the small geometric helpers every EKF file shares.
//
// The state (robot_localization's 15 components plus six calibration states) describes
// base_link in the map frame (REP-105, x east, y north, z up; REP-103 SI units):
//   position        x, y, z            map frame                                 [m]
//   orientation     roll, pitch, yaw   map_R_base = Rz(yaw) Ry(pitch) Rx(roll)   [rad]
//   linear velocity vx, vy, vz         base_link frame                           [m/s]
//   angular rate    wx, wy, wz         base_link frame                           [rad/s]
//   acceleration    ax, ay, az         base_link frame, gravity excluded         [m/s^2]
//   twist scale     s                  the INS linear twist reads (1 + s) v      [-]
//   GNSS bias       bx, by             the receiver's slow error, map frame      [m]
//   gyro bias       gx, gy, gz         the IMU's rate error, base_link frame     [rad/s]
// Angles are kept wrapped to [-pi, pi). The Euler parameterisation is singular at |pitch| =
// pi/2, which a ground vehicle never reaches; the models clamp cos(pitch) away from zero so no
// division by zero can occur, but near the singularity results are meaningless.
//
// Why 15 kinematic states and not fewer: the matcher observes x, y, yaw (and optionally z, roll,
// pitch); the Applanix gives body twist; the IMU gives rates, specific force and roll/pitch.
// Keeping the body acceleration as a state lets the accelerometer contribute (between scan matches
// and when the odometry twist drops out) at the price of six states that are cheap at this size.
// The accelerometer's bias is not estimated (the INS twist holds the velocity); the gyro's is
// (below), as an IMU that its INS does not compensate leans the heading.
//
// Why the twist scale: an INS measures distance with a scale error of a few tenths of a percent
// (wheel or DMI calibration, tyre pressure). Its twist is far more precise than that (mm/s), so a
// filter that takes it as unbiased follows it and runs ahead of (or behind) the scan matches in
// proportion to the speed: 0.2 % at 12 m/s is 2.4 cm/s, which between matches that weigh little
// against the twist built a steady 2-4 cm lead on the simulated drives (docs/evaluation.md). With
// s in the state the matches calibrate the twist (s is observable whenever the vehicle moves) and
// v is the true body velocity. s is a slow random walk; it is kept by setPose() (a relocalization
// does not change the INS) and starts at 0 on reset().
//
// Why the GNSS bias: a receiver's error is mostly slow (multipath, atmosphere, orbits: metres
// that change over minutes), not white. Fused as independent fixes, the mean of a few hundred of
// them was taken for the truth: the covariance shrank to decimetres while the error stayed at
// the bias. With b = (bx, by) in the state a fix reads p + b (EkfOptions::estimate_gnss_bias);
// b is a first-order Gauss-Markov process (stationary sigma gnss_bias_sigma_m, correlation time
// gnss_bias_tau_s), so from fixes alone the position stays as uncertain as the bias, and where
// scan matches pin the position the fixes calibrate b instead of pulling the pose. Kept by
// setPose(); starts at 0 with its stationary variance on reset().
//
// Why the gyro bias: an IMU's rates carry a bias of a fraction of a mrad/s that the INS twist's
// rates do not (they come from the INS's own, compensated solution). Fused as unbiased, the two
// rate sources disagree and the filter's heading leans by a few tenths of a mrad between the
// weak heading of the matches (floor 0.01 rad); at speed that is a steady lateral drift that the
// matches correct only after it has built up (+0.3-0.4 cm beside them on the simulated drives).
// With g in the state the IMU reads w + g (EkfOptions::estimate_gyro_bias): the INS rates, or
// the matched heading without them, calibrate it. A slow random walk; kept by setPose().

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {

/// Index of each component in the EKF state vector (see the table at the top of this file).
enum StateIndex : int {
  kStateX = 0,
  kStateY,
  kStateZ,
  kStateRoll,
  kStatePitch,
  kStateYaw,
  kStateVx,
  kStateVy,
  kStateVz,
  kStateWx,
  kStateWy,
  kStateWz,
  kStateAx,
  kStateAy,
  kStateAz,
  kStateTwistScale,  ///< s: INS linear twist = (1 + s) x true body velocity
  kStateGnssBiasX,   ///< the GNSS receiver's bias along the map's x [m]
  kStateGnssBiasY,   ///< ... along y [m]
  kStateGyroBiasX,   ///< the IMU gyro's bias about base_link's x [rad/s]
  kStateGyroBiasY,   ///< ... about y
  kStateGyroBiasZ,   ///< ... about z
  kStateSize         ///< number of states (21)
};

/// States with an entry in EkfOptions::process_noise_density and initial_variance (the GNSS and
/// gyro biases follow their own parameters instead, EkfOptions::gnss_bias_*, gyro_bias_*).
constexpr int kTunedStateCount = kStateGnssBiasX;

/// First index of each 3-vector block.
constexpr int kPositionBlock = kStateX;
constexpr int kOrientationBlock = kStateRoll;
constexpr int kLinearVelocityBlock = kStateVx;
constexpr int kAngularVelocityBlock = kStateWx;
constexpr int kLinearAccelerationBlock = kStateAx;

using StateVector = Eigen::Matrix<double, kStateSize, 1>;
using StateCovariance = Eigen::Matrix<double, kStateSize, kStateSize>;

/// Short name of a state component ("x", "yaw", "vx", ...) for reasons and diagnostics;
/// "?" for an index outside [0, kStateSize).
const char* stateName(int index);

/// True for roll, pitch and yaw: components whose differences are wrapped.
inline bool isAngleState(int index) {
  return index == kStateRoll || index == kStatePitch || index == kStateYaw;
}

/// Wraps an angle to [-pi, pi). Non-finite input is returned unchanged.
double wrapAngle(double angle_rad);

/// map_R_base for ZYX Euler angles: Rz(yaw) * Ry(pitch) * Rx(roll).
Eigen::Matrix3d rotationFromRpy(double roll_rad, double pitch_rad, double yaw_rad);

/// ZYX Euler angles (roll, pitch, yaw) of a rotation matrix, each in [-pi, pi], pitch in
/// [-pi/2, pi/2]. Inverse of rotationFromRpy away from the pitch singularity.
Eigen::Vector3d rpyFromRotation(const Eigen::Matrix3d& rotation);

/// One filter state: mean and covariance at a time.
struct EkfState {
  double time_s = 0.0;  ///< time of validity [s], the caller's clock (e.g. ROS stamp in seconds)
  StateVector x = StateVector::Zero();
  StateCovariance P = StateCovariance::Identity();

  /// map_T_base: the pose of base_link in the map frame.
  Eigen::Isometry3d pose() const;
  /// Covariance of (x, y, z, roll, pitch, yaw), the order of geometry_msgs PoseWithCovariance.
  Matrix6d poseCovariance() const { return P.block<6, 6>(kStateX, kStateX); }
  /// Body-frame linear velocity of base_link [m/s].
  Eigen::Vector3d linearVelocity() const { return x.segment<3>(kLinearVelocityBlock); }
  /// Body-frame angular velocity of base_link [rad/s].
  Eigen::Vector3d angularVelocity() const { return x.segment<3>(kAngularVelocityBlock); }
  /// Body-frame acceleration of base_link without gravity [m/s^2].
  Eigen::Vector3d linearAcceleration() const { return x.segment<3>(kLinearAccelerationBlock); }
  /// Scale error s of the INS linear twist (which reads (1 + s) times the true velocity) [-].
  double twistScale() const { return x(kStateTwistScale); }
  /// The GNSS receiver's bias in the map frame (a fix reads position + bias) [m].
  Eigen::Vector2d gnssBias() const { return x.segment<2>(kStateGnssBiasX); }
  /// The IMU gyro's bias in base_link (the IMU reads w + bias) [rad/s].
  Eigen::Vector3d gyroBias() const { return x.segment<3>(kStateGyroBiasX); }
  /// Covariance of (vx, vy, vz, wx, wy, wz), the order of geometry_msgs TwistWithCovariance.
  Matrix6d twistCovariance() const { return P.block<6, 6>(kStateVx, kStateVx); }
};

/// Writes a pose (map_T_base) into the position and orientation components of x.
void setPoseInState(const Eigen::Isometry3d& map_T_base, StateVector* x);

}  // namespace gmm_localization
