#include "gmm_localization/core/filter/ekf_measurement.h"

#include <cmath>
#include <sstream>

#include <Eigen/Cholesky>

namespace gmm_localization {
namespace {

std::string prefix(MeasurementSource source, double stamp_s) {
  std::ostringstream s;
  s.precision(15);
  s << sourceName(source) << " measurement at t=" << stamp_s << " s: ";
  return s.str();
}

// Validates values and covariance of n observed components and assembles the measurement.
Result<EkfMeasurement> assemble(MeasurementSource source, MeasurementModel model, double stamp_s,
                                const std::array<int, kMaxMeasurementSize>& indices,
                                const MeasurementVector& z, const MeasurementCovariance& cov,
                                const EkfOptions& options) {
  const int n = static_cast<int>(z.size());
  if (!std::isfinite(stamp_s)) {
    return Result<EkfMeasurement>::failure(prefix(source, stamp_s) + "stamp is not finite");
  }
  if (n == 0) {
    return Result<EkfMeasurement>::failure(prefix(source, stamp_s) +
                                           "no component selected for fusion");
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(z(i))) {
      std::ostringstream s;
      s << prefix(source, stamp_s) << stateName(indices[i]) << " value is not finite (" << z(i)
        << ")";
      return Result<EkfMeasurement>::failure(s.str());
    }
  }
  if (!cov.allFinite()) {
    return Result<EkfMeasurement>::failure(prefix(source, stamp_s) +
                                           "covariance has a non-finite entry");
  }
  const double scale = 1.0 + cov.cwiseAbs().maxCoeff();
  for (int i = 0; i < n; ++i) {
    if (cov(i, i) < 0.0) {
      std::ostringstream s;
      s << prefix(source, stamp_s) << "negative variance " << cov(i, i) << " for "
        << stateName(indices[i]);
      return Result<EkfMeasurement>::failure(s.str());
    }
    for (int j = 0; j < i; ++j) {
      if (std::abs(cov(i, j) - cov(j, i)) > 1e-9 * scale) {
        std::ostringstream s;
        s << prefix(source, stamp_s) << "covariance is not symmetric at (" << stateName(indices[i])
          << ", " << stateName(indices[j]) << ")";
        return Result<EkfMeasurement>::failure(s.str());
      }
    }
  }
  EkfMeasurement m;
  m.source = source;
  m.model = model;
  m.stamp_s = stamp_s;
  m.size = n;
  m.indices = indices;
  m.z = z;
  m.R = 0.5 * (cov + cov.transpose());
  for (int i = 0; i < n; ++i) m.R(i, i) = std::max(m.R(i, i), options.min_measurement_variance);
  Eigen::LLT<MeasurementCovariance> llt(m.R);
  if (llt.info() != Eigen::Success) {
    return Result<EkfMeasurement>::failure(prefix(source, stamp_s) +
                                           "covariance is not positive definite");
  }
  return m;
}

// Selects the rows/columns flagged in mask from a 6-vector and its 6x6 covariance.
void select6(const std::array<bool, 6>& mask, int first_state, const Vector6d& values,
             const Matrix6d& cov, std::array<int, kMaxMeasurementSize>* indices,
             MeasurementVector* z, MeasurementCovariance* r) {
  int rows[6];
  int n = 0;
  for (int i = 0; i < 6; ++i) {
    if (mask[i]) rows[n++] = i;
  }
  z->resize(n);
  r->resize(n, n);
  for (int a = 0; a < n; ++a) {
    (*indices)[a] = first_state + rows[a];
    (*z)(a) = values(rows[a]);
    for (int b = 0; b < n; ++b) (*r)(a, b) = cov(rows[a], rows[b]);
  }
}

Result<EkfMeasurement> threeAxis(MeasurementSource source, MeasurementModel model, double stamp_s,
                                 int first_state, const Eigen::Vector3d& v,
                                 const Eigen::Matrix3d& cov, const EkfOptions& options) {
  std::array<int, kMaxMeasurementSize> indices{first_state, first_state + 1, first_state + 2};
  return assemble(source, model, stamp_s, indices, v, cov, options);
}

// Unit quaternion of an IMU message, or a reason.
Result<Eigen::Quaterniond> imuOrientation(const ImuMeasurement& m, MeasurementSource source) {
  const Eigen::Vector4d c = m.orientation.coeffs();
  if (!c.allFinite()) {
    return Result<Eigen::Quaterniond>::failure(prefix(source, m.stamp_s) +
                                               "orientation is not finite");
  }
  if (c.norm() < 1e-6) {
    return Result<Eigen::Quaterniond>::failure(prefix(source, m.stamp_s) +
                                               "orientation quaternion has zero norm");
  }
  return m.orientation.normalized();
}

}  // namespace

const char* sourceName(MeasurementSource source) {
  switch (source) {
    case MeasurementSource::kImuOrientation:
      return "imu_orientation";
    case MeasurementSource::kImuAngularVelocity:
      return "imu_angular_velocity";
    case MeasurementSource::kImuLinearAcceleration:
      return "imu_linear_acceleration";
    case MeasurementSource::kTwist:
      return "twist";
    case MeasurementSource::kPose:
      return "pose";
    case MeasurementSource::kCovarianceFloor:
      return "covariance_floor";
    case MeasurementSource::kGnssPosition:
      return "gnss";
    case MeasurementSource::kCount:
      break;
  }
  return "unknown";
}

PoseMeasurement PoseMeasurement::planar(double stamp_s, double x_m, double y_m, double yaw_rad,
                                        const Eigen::Matrix3d& covariance_xy_yaw) {
  PoseMeasurement p;
  p.stamp_s = stamp_s;
  p.map_T_base = Eigen::Isometry3d::Identity();
  p.map_T_base.translation() = Eigen::Vector3d(x_m, y_m, 0.0);
  p.map_T_base.linear() = rotationFromRpy(0.0, 0.0, yaw_rad);
  p.covariance = poseCovarianceFromPlanar(covariance_xy_yaw);
  p.mask = {true, true, false, false, false, true};
  return p;
}

PoseMeasurement PoseMeasurement::full(double stamp_s, const Eigen::Isometry3d& map_T_base,
                                      const Matrix6d& covariance) {
  PoseMeasurement p;
  p.stamp_s = stamp_s;
  p.map_T_base = map_T_base;
  p.covariance = covariance;
  return p;
}

Result<TwistMeasurement> twistFromOdometryIncrement(const Eigen::Isometry3d& odom_T_base_prev,
                                                    double t_prev_s,
                                                    const Eigen::Isometry3d& odom_T_base,
                                                    double t_s, const Matrix6d& covariance) {
  const double dt = t_s - t_prev_s;
  if (!std::isfinite(dt) || !(dt > 0.0)) {
    return Result<TwistMeasurement>::failure(
        "odometry increment: stamps must be finite and increasing");
  }
  if (!odom_T_base_prev.matrix().allFinite() || !odom_T_base.matrix().allFinite()) {
    return Result<TwistMeasurement>::failure("odometry increment: pose is not finite");
  }
  const Eigen::Isometry3d delta = odom_T_base_prev.inverse() * odom_T_base;
  const Eigen::AngleAxisd rotation(delta.linear());
  TwistMeasurement t;
  t.stamp_s = t_s;
  t.linear_mps = delta.translation() / dt;
  t.angular_radps = rotation.axis() * rotation.angle() / dt;
  t.covariance = covariance;
  return t;
}

Result<EkfMeasurement> makePoseMeasurement(const PoseMeasurement& m, const EkfOptions& options) {
  const MeasurementSource source = MeasurementSource::kPose;
  if (!m.map_T_base.matrix().allFinite()) {
    return Result<EkfMeasurement>::failure(prefix(source, m.stamp_s) + "pose is not finite");
  }
  const Eigen::Matrix3d r = m.map_T_base.linear();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      r.determinant() <= 0.0) {
    return Result<EkfMeasurement>::failure(prefix(source, m.stamp_s) +
                                           "pose linear part is not a rotation");
  }
  Vector6d values;
  values << m.map_T_base.translation(), rpyFromRotation(r);
  std::array<int, kMaxMeasurementSize> indices{};
  MeasurementVector z;
  MeasurementCovariance cov;
  select6(m.mask, kStateX, values, m.covariance, &indices, &z, &cov);
  return assemble(source, MeasurementModel::kDirect, m.stamp_s, indices, z, cov, options);
}

Result<EkfMeasurement> makePositionMeasurement(const PositionMeasurement& m,
                                               const EkfOptions& options) {
  const int n = m.use_z ? 3 : 2;
  std::array<int, kMaxMeasurementSize> indices{kStateX, kStateY, kStateZ};
  const MeasurementModel model =
      options.estimate_gnss_bias ? MeasurementModel::kBiasedPosition : MeasurementModel::kDirect;
  return assemble(MeasurementSource::kGnssPosition, model, m.stamp_s, indices, m.position_m.head(n),
                  m.covariance.topLeftCorner(n, n), options);
}

Result<EkfMeasurement> makeTwistMeasurement(const TwistMeasurement& m, const EkfOptions& options) {
  std::array<bool, 6> mask = m.mask;
  for (int i = 0; i < 3; ++i) {
    mask[i] = mask[i] && options.twist_use_linear;
    mask[i + 3] = mask[i + 3] && options.twist_use_angular;
  }
  Vector6d values;
  values << m.linear_mps, m.angular_radps;
  std::array<int, kMaxMeasurementSize> indices{};
  MeasurementVector z;
  MeasurementCovariance cov;
  select6(mask, kStateVx, values, m.covariance, &indices, &z, &cov);
  const MeasurementModel model =
      options.estimate_twist_scale ? MeasurementModel::kScaledTwist : MeasurementModel::kDirect;
  return assemble(MeasurementSource::kTwist, model, m.stamp_s, indices, z, cov, options);
}

Result<EkfMeasurement> makeImuOrientationMeasurement(const ImuMeasurement& m,
                                                     const EkfOptions& options) {
  const MeasurementSource source = MeasurementSource::kImuOrientation;
  if (!m.has_orientation || !options.imu_use_orientation) {
    return Result<EkfMeasurement>::failure(prefix(source, m.stamp_s) + "not present or disabled");
  }
  const auto q = imuOrientation(m, source);
  if (!q) return Result<EkfMeasurement>::failure(q.error());
  const Eigen::Vector3d rpy = rpyFromRotation(q->toRotationMatrix());
  std::array<int, kMaxMeasurementSize> indices{kStateRoll, kStatePitch};
  return assemble(source, MeasurementModel::kDirect, m.stamp_s, indices, rpy.head<2>(),
                  m.orientation_covariance.topLeftCorner<2, 2>(), options);
}

Result<EkfMeasurement> makeImuAngularVelocityMeasurement(const ImuMeasurement& m,
                                                         const EkfOptions& options) {
  const MeasurementSource source = MeasurementSource::kImuAngularVelocity;
  if (!m.has_angular_velocity || !options.imu_use_angular_velocity) {
    return Result<EkfMeasurement>::failure(prefix(source, m.stamp_s) + "not present or disabled");
  }
  const MeasurementModel model =
      options.estimate_gyro_bias ? MeasurementModel::kBiasedRate : MeasurementModel::kDirect;
  return threeAxis(source, model, m.stamp_s, kStateWx, m.angular_velocity_radps,
                   m.angular_velocity_covariance, options);
}

Result<EkfMeasurement> makeImuAccelerationMeasurement(const ImuMeasurement& m,
                                                      const EkfOptions& options) {
  const MeasurementSource source = MeasurementSource::kImuLinearAcceleration;
  if (!m.has_linear_acceleration || !options.imu_use_linear_acceleration) {
    return Result<EkfMeasurement>::failure(prefix(source, m.stamp_s) + "not present or disabled");
  }
  if (options.imu_gravity_removal == GravityRemoval::kStateEstimate) {
    return threeAxis(source, MeasurementModel::kAccelerationMinusGravity, m.stamp_s, kStateAx,
                     m.linear_acceleration_mps2, m.linear_acceleration_covariance, options);
  }
  if (!m.has_orientation) {
    return Result<EkfMeasurement>::failure(
        prefix(source, m.stamp_s) +
        "gravity removal by measured orientation needs the message's orientation");
  }
  const auto q = imuOrientation(m, source);
  if (!q) return Result<EkfMeasurement>::failure(q.error());
  // f = a - R^T g_map with g_map = (0, 0, -g), so a = f - R^T (0, 0, g). The orientation's
  // roll/pitch noise enters a through the gravity term: add J Sigma_rp J^T to the covariance.
  const Eigen::Matrix2d tilt_cov = m.orientation_covariance.topLeftCorner<2, 2>();
  if (!tilt_cov.allFinite() || tilt_cov(0, 0) < 0.0 || tilt_cov(1, 1) < 0.0) {
    return Result<EkfMeasurement>::failure(
        prefix(source, m.stamp_s) +
        "gravity removal by measured orientation needs a valid roll/pitch covariance");
  }
  const Eigen::Vector3d rpy = rpyFromRotation(q->toRotationMatrix());
  const double sr = std::sin(rpy.x()), cr = std::cos(rpy.x());
  const double sp = std::sin(rpy.y()), cp = std::cos(rpy.y());
  const Eigen::Vector3d up_in_body(-sp, sr * cp, cr * cp);
  Eigen::Matrix<double, 3, 2> j;
  j.col(0) = options.gravity_mps2 * Eigen::Vector3d(0.0, cr * cp, -sr * cp);
  j.col(1) = options.gravity_mps2 * Eigen::Vector3d(-cp, -sr * sp, -cr * sp);
  return threeAxis(source, MeasurementModel::kDirect, m.stamp_s, kStateAx,
                   m.linear_acceleration_mps2 - options.gravity_mps2 * up_in_body,
                   m.linear_acceleration_covariance + j * tilt_cov * j.transpose(), options);
}

void evaluateMeasurement(const EkfMeasurement& m, const StateVector& x, double gravity_mps2,
                         MeasurementVector* h, MeasurementJacobian* jacobian) {
  h->resize(m.size);
  jacobian->setZero(m.size, kStateSize);
  for (int i = 0; i < m.size; ++i) {
    (*h)(i) = x(m.indices[i]);
    (*jacobian)(i, m.indices[i]) = 1.0;
  }
  if (m.model == MeasurementModel::kScaledTwist) {
    // The INS reads (1 + s) times the true velocity: h = (1 + s) v_k, dh/dv_k = 1 + s,
    // dh/ds = v_k. Its rates are gyro rates, unscaled.
    const double gain = 1.0 + x(kStateTwistScale);
    for (int i = 0; i < m.size; ++i) {
      const int k = m.indices[i];
      if (k < kStateVx || k > kStateVz) continue;
      (*h)(i) = gain * x(k);
      (*jacobian)(i, k) = gain;
      (*jacobian)(i, kStateTwistScale) = x(k);
    }
  }
  if (m.model == MeasurementModel::kBiasedPosition) {
    // A fix reads the position plus the receiver's bias, horizontally (ekf_state.h).
    for (int i = 0; i < m.size; ++i) {
      const int k = m.indices[i];
      if (k != kStateX && k != kStateY) continue;
      const int b = k == kStateX ? kStateGnssBiasX : kStateGnssBiasY;
      (*h)(i) += x(b);
      (*jacobian)(i, b) = 1.0;
    }
  }
  if (m.model == MeasurementModel::kBiasedRate) {
    // The gyro reads the body rate plus its bias (ekf_state.h).
    for (int i = 0; i < m.size; ++i) {
      const int b = kStateGyroBiasX + (m.indices[i] - kStateWx);
      (*h)(i) += x(b);
      (*jacobian)(i, b) = 1.0;
    }
  }
  if (m.model == MeasurementModel::kAccelerationMinusGravity) {
    // Specific force f = a + R(roll, pitch)^T (0, 0, g): gravity seen from the body, with its
    // partial derivatives in roll and pitch (yaw does not enter).
    const double sr = std::sin(x(kStateRoll)), cr = std::cos(x(kStateRoll));
    const double sp = std::sin(x(kStatePitch)), cp = std::cos(x(kStatePitch));
    const Eigen::Vector3d up_in_body(-sp, sr * cp, cr * cp);
    const Eigen::Vector3d d_roll(0.0, cr * cp, -sr * cp);
    const Eigen::Vector3d d_pitch(-cp, -sr * sp, -cr * sp);
    for (int i = 0; i < m.size; ++i) {
      const int axis = m.indices[i] - kStateAx;
      (*h)(i) += gravity_mps2 * up_in_body(axis);
      (*jacobian)(i, kStateRoll) = gravity_mps2 * d_roll(axis);
      (*jacobian)(i, kStatePitch) = gravity_mps2 * d_pitch(axis);
    }
  }
}

}  // namespace gmm_localization
