#pragma once
// EKF measurements: the sensor inputs the filter accepts, their validation, and the
// measurement models h(x) with their Jacobians H.
//
// Inputs are already expressed in base_link (the ROS layer rotates IMU data with the TF
// extrinsic) and carry a stamp in seconds on the caller's clock. Covariances follow ROS message
// order. Validation rejects, with a reason, any non-finite value or stamp, a negative variance,
// an asymmetric or non-positive-definite covariance: nothing invalid ever reaches the state.
//
// Odometry: the Applanix pose lives in the drifting odom frame and is never fused as absolute.
// Its twist (base_link) is fused directly (TwistMeasurement). A source that only gives poses
// can be fused in "differential" mode with twistFromOdometryIncrement(), which turns two
// consecutive odom poses into the body twist that moved between them; fuse either that or the
// source's own twist, not both (the same information would be counted twice).

#include <array>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/filter/ekf_options.h"
#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {

/// Which sensor stream a measurement came from; diagnostics are kept per source.
enum class MeasurementSource : int {
  kImuOrientation = 0,     ///< roll, pitch from an IMU orientation
  kImuAngularVelocity,     ///< body rates from an IMU
  kImuLinearAcceleration,  ///< body acceleration from an IMU specific force
  kTwist,                  ///< body twist from odometry (Applanix INS)
  kPose,                   ///< absolute pose in map (scan matcher, relocalization)
  kCovarianceFloor,        ///< the matcher does not confirm the estimate: variances raised
  kGnssPosition,           ///< absolute position in map from a GNSS fix (optional input)
  kCount
};
constexpr int kMeasurementSourceCount = static_cast<int>(MeasurementSource::kCount);

/// Short name of a source ("imu_orientation", "twist", "pose", ...).
const char* sourceName(MeasurementSource source);

/// One sensor_msgs/Imu sample in base_link. Each part is used when its has_ flag is set (and
/// the matching EkfOptions::imu_use_ flag); parts are validated and fused independently.
struct ImuMeasurement {
  double stamp_s = 0.0;  ///< [s]
  /// Orientation of base_link relative to a gravity-aligned frame with arbitrary yaw; only its
  /// roll and pitch (ZYX) are fused.
  bool has_orientation = false;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  /// Covariance of (roll, pitch, yaw) [rad^2]; only the roll/pitch block is read.
  Eigen::Matrix3d orientation_covariance = Eigen::Matrix3d::Zero();
  bool has_angular_velocity = false;
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();       ///< body rates [rad/s]
  Eigen::Matrix3d angular_velocity_covariance = Eigen::Matrix3d::Zero();  ///< [(rad/s)^2]
  /// Specific force as an accelerometer reports it, gravity included (+g on z at rest, level).
  bool has_linear_acceleration = false;
  Eigen::Vector3d linear_acceleration_mps2 = Eigen::Vector3d::Zero();        ///< [m/s^2]
  Eigen::Matrix3d linear_acceleration_covariance = Eigen::Matrix3d::Zero();  ///< [(m/s^2)^2]
};

/// Body twist of base_link (nav_msgs/Odometry twist). The used components (mask, in the order
/// vx, vy, vz, wx, wy, wz, further restricted by EkfOptions::twist_use_*) must be finite;
/// only their covariance block is read.
struct TwistMeasurement {
  double stamp_s = 0.0;                                             ///< [s]
  Eigen::Vector3d linear_mps = Eigen::Vector3d::Zero();             ///< [m/s]
  Eigen::Vector3d angular_radps = Eigen::Vector3d::Zero();          ///< [rad/s]
  Matrix6d covariance = Matrix6d::Zero();                           ///< (v, w) order
  std::array<bool, 6> mask = {true, true, true, true, true, true};  ///< components to fuse
};

/// Absolute pose of base_link in the map frame (scan match). mask selects which of
/// (x, y, z, roll, pitch, yaw) are fused; only that block of covariance is read and must be
/// finite and positive definite. A 3-DOF match fuses x, y, yaw with its 3x3 covariance.
struct PoseMeasurement {
  double stamp_s = 0.0;                                          ///< [s]
  Eigen::Isometry3d map_T_base = Eigen::Isometry3d::Identity();  ///< linear part a rotation
  Matrix6d covariance = Matrix6d::Zero();  ///< (x, y, z, roll, pitch, yaw) [m^2, rad^2]
  std::array<bool, 6> mask = {true, true, true, true, true, true};

  /// x, y, yaw with the 3x3 covariance of (x, y, yaw); z, roll, pitch not fused.
  static PoseMeasurement planar(double stamp_s, double x_m, double y_m, double yaw_rad,
                                const Eigen::Matrix3d& covariance_xy_yaw);
  /// All six components with their 6x6 covariance.
  static PoseMeasurement full(double stamp_s, const Eigen::Isometry3d& map_T_base,
                              const Matrix6d& covariance);
};

/// Absolute position of base_link in the map frame, e.g. a GNSS fix placed in the map through
/// its georeference (core/localization/gnss_position.h). x, y are fused, z too when use_z;
/// covariance of (x, y, z) [m^2], only the fused block is read.
struct PositionMeasurement {
  double stamp_s = 0.0;  ///< [s]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  bool use_z = false;
};

/// Differential mode for a pose-only odometry source: the body twist that carries
/// odom_T_base_prev (at t_prev_s) to odom_T_base (at t_s), i.e. the increment
/// base_prev_T_base as (translation, rotation vector) divided by dt, stamped at t_s, with the
/// given twist covariance (the caller's, e.g. increment covariance / dt^2). Fails when dt is
/// not positive or any input is non-finite.
Result<TwistMeasurement> twistFromOdometryIncrement(const Eigen::Isometry3d& odom_T_base_prev,
                                                    double t_prev_s,
                                                    const Eigen::Isometry3d& odom_T_base,
                                                    double t_s, const Matrix6d& covariance);

// ---- Internal form shared by the filter and its history --------------------------------------

constexpr int kMaxMeasurementSize = 6;
using MeasurementVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxMeasurementSize, 1>;
using MeasurementCovariance = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0,
                                            kMaxMeasurementSize, kMaxMeasurementSize>;
using MeasurementJacobian = Eigen::Matrix<double, Eigen::Dynamic, kStateSize, Eigen::RowMajor,
                                          kMaxMeasurementSize, kStateSize>;

/// How z relates to the state.
enum class MeasurementModel {
  kDirect,                    ///< z = x[indices]
  kAccelerationMinusGravity,  ///< z = specific force f; h(x) = a + R(roll, pitch)^T g_up
  kScaledTwist,               ///< INS twist: h(x) = (1 + s) v for vx, vy, vz rows, w for the rest
  kBiasedPosition,            ///< GNSS fix: h(x) = p + b for the x, y rows (b: the receiver's
                              ///< bias, EkfOptions::estimate_gnss_bias), z for the z row
  kBiasedRate,                ///< IMU rates: h(x) = w + g (g: the gyro's bias,
                              ///< EkfOptions::estimate_gyro_bias)
  /// Not an observation: the indexed components' variances are raised to at least z (their
  /// correlations dropped), never gated. Kept in the history like a measurement, so that a
  /// pose fused later at an earlier stamp, or one stamped after it, sees it in time order.
  kCovarianceFloor,
};

/// A validated measurement of `size` state components (at most 6).
struct EkfMeasurement {
  MeasurementSource source = MeasurementSource::kPose;
  MeasurementModel model = MeasurementModel::kDirect;
  double stamp_s = 0.0;
  int size = 0;
  std::array<int, kMaxMeasurementSize> indices{};  ///< observed StateIndex per row
  MeasurementVector z;
  MeasurementCovariance R;
};

/// Validated internal measurements, or the reason the input is rejected. Each applies
/// min_measurement_variance as a diagonal floor. A twist is kScaledTwist when
/// EkfOptions::estimate_twist_scale is set, else kDirect. An IMU or twist whose used parts are all
/// disabled fails with a reason saying so.
Result<EkfMeasurement> makePoseMeasurement(const PoseMeasurement& m, const EkfOptions& options);
Result<EkfMeasurement> makeTwistMeasurement(const TwistMeasurement& m, const EkfOptions& options);
/// Source kGnssPosition on x, y (and z): model kBiasedPosition with
/// EkfOptions::estimate_gnss_bias, else kDirect.
Result<EkfMeasurement> makePositionMeasurement(const PositionMeasurement& m,
                                               const EkfOptions& options);
Result<EkfMeasurement> makeImuOrientationMeasurement(const ImuMeasurement& m,
                                                     const EkfOptions& options);
Result<EkfMeasurement> makeImuAngularVelocityMeasurement(const ImuMeasurement& m,
                                                         const EkfOptions& options);
/// With GravityRemoval::kMeasuredOrientation the gravity is removed here with the message's
/// orientation (model kDirect on a); with kStateEstimate it is removed at fusion time.
Result<EkfMeasurement> makeImuAccelerationMeasurement(const ImuMeasurement& m,
                                                      const EkfOptions& options);

/// Predicted measurement h(x) and Jacobian H (size x kStateSize) at state x. For
/// kAccelerationMinusGravity, H has identity on a and the partials of R^T g_up in roll and
/// pitch (see GravityRemoval::kStateEstimate). For kScaledTwist a linear row k has (1 + s) on
/// v_k and v_k on s (EkfOptions::estimate_twist_scale). For kBiasedPosition the x and y rows
/// have 1 on the position and 1 on the bias of that axis; for kBiasedRate each row has 1 on the
/// rate and 1 on the gyro bias of that axis.
void evaluateMeasurement(const EkfMeasurement& m, const StateVector& x, double gravity_mps2,
                         MeasurementVector* h, MeasurementJacobian* jacobian);

}  // namespace gmm_localization
