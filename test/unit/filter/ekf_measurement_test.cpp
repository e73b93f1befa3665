// EKF measurement validation and models: every invalid input is rejected with a reason.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "gmm_localization/core/filter/ekf_measurement.h"

namespace gmm_localization {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Matrix3d planarCov() {
  Eigen::Matrix3d c;
  c << 0.04, 0.01, 0.001, 0.01, 0.09, 0.0, 0.001, 0.0, 0.0004;
  return c;
}

/// The measurement Jacobian by central differences of evaluateMeasurement in every state.
MeasurementJacobian numericJacobian(const EkfMeasurement& m, const StateVector& x, double g) {
  MeasurementJacobian numeric(m.size, kStateSize);
  for (int j = 0; j < kStateSize; ++j) {
    StateVector xp = x, xm = x;
    xp(j) += 1e-6;
    xm(j) -= 1e-6;
    MeasurementVector hp, hm;
    MeasurementJacobian unused;
    evaluateMeasurement(m, xp, g, &hp, &unused);
    evaluateMeasurement(m, xm, g, &hm, &unused);
    numeric.col(j) = (hp - hm) / 2e-6;
  }
  return numeric;
}

/// Expects the analytic Jacobian `jac` of m at x to match the numeric one in every entry.
void expectJacobianMatchesNumeric(const EkfMeasurement& m, const StateVector& x, double g,
                                  const MeasurementJacobian& jac) {
  const MeasurementJacobian numeric = numericJacobian(m, x, g);
  for (int j = 0; j < kStateSize; ++j) {
    for (int i = 0; i < m.size; ++i) {
      EXPECT_NEAR(jac(i, j), numeric(i, j), 1e-6) << "d h" << i << " / d " << stateName(j);
    }
  }
}

TEST(EkfMeasurement, PlanarPoseSelectsXYYaw) {
  EkfOptions o;
  const auto m = makePoseMeasurement(PoseMeasurement::planar(3.0, 1.0, 2.0, 0.5, planarCov()), o);
  ASSERT_TRUE(m.ok()) << m.error();
  ASSERT_EQ(m->size, 3);
  EXPECT_EQ(m->indices[0], kStateX);
  EXPECT_EQ(m->indices[1], kStateY);
  EXPECT_EQ(m->indices[2], kStateYaw);
  EXPECT_NEAR(m->z(2), 0.5, 1e-12);
  EXPECT_TRUE(m->R.isApprox(planarCov()));
  EXPECT_EQ(m->source, MeasurementSource::kPose);
}

TEST(EkfMeasurement, NonFiniteInputsAreRejectedWithAReason) {
  EkfOptions o;
  PoseMeasurement p = PoseMeasurement::planar(3.0, 1.0, 2.0, 0.5, planarCov());
  auto bad = p;
  bad.map_T_base.translation().x() = kNaN;
  auto r = makePoseMeasurement(bad, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("not finite"), std::string::npos) << r.error();
  bad = p;
  bad.covariance(0, 0) = kInf;
  r = makePoseMeasurement(bad, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("non-finite"), std::string::npos) << r.error();
  bad = p;
  bad.stamp_s = kNaN;
  EXPECT_FALSE(makePoseMeasurement(bad, o).ok());
  // An unused covariance entry may hold anything: only the fused block is read.
  bad = p;
  bad.covariance(2, 2) = kNaN;
  EXPECT_TRUE(makePoseMeasurement(bad, o).ok());

  TwistMeasurement t;
  t.stamp_s = 1.0;
  t.covariance = Matrix6d::Identity() * 0.01;
  t.angular_radps.z() = kNaN;
  r = makeTwistMeasurement(t, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("wz"), std::string::npos) << r.error();

  ImuMeasurement imu;
  imu.stamp_s = 1.0;
  imu.has_orientation = true;
  imu.orientation.coeffs() << kNaN, 0.0, 0.0, 1.0;
  imu.orientation_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  EXPECT_FALSE(makeImuOrientationMeasurement(imu, o).ok());
  imu.orientation.coeffs().setZero();
  EXPECT_FALSE(makeImuOrientationMeasurement(imu, o).ok());
}

TEST(EkfMeasurement, BadCovariancesAreRejected) {
  EkfOptions o;
  Eigen::Matrix3d c = planarCov();
  c(1, 1) = -0.1;
  auto r = makePoseMeasurement(PoseMeasurement::planar(1.0, 0, 0, 0, c), o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("negative variance"), std::string::npos) << r.error();
  c = planarCov();
  c(0, 1) = 0.02;  // c(1, 0) stays 0.01
  r = makePoseMeasurement(PoseMeasurement::planar(1.0, 0, 0, 0, c), o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("not symmetric"), std::string::npos) << r.error();
  c << 1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0;  // indefinite
  r = makePoseMeasurement(PoseMeasurement::planar(1.0, 0, 0, 0, c), o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("positive definite"), std::string::npos) << r.error();
  // A zero covariance is floored to min_measurement_variance, not rejected.
  r = makePoseMeasurement(PoseMeasurement::planar(1.0, 0, 0, 0, Eigen::Matrix3d::Zero()), o);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_DOUBLE_EQ(r->R(0, 0), o.min_measurement_variance);
}

TEST(EkfMeasurement, NonRotationPoseIsRejected) {
  EkfOptions o;
  PoseMeasurement p =
      PoseMeasurement::full(1.0, Eigen::Isometry3d::Identity(), Matrix6d::Identity() * 0.01);
  p.map_T_base.linear()(0, 0) = 2.0;
  const auto r = makePoseMeasurement(p, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("not a rotation"), std::string::npos) << r.error();
}

TEST(EkfMeasurement, TwistMaskAndOptionsSelectComponents) {
  EkfOptions o;
  o.twist_use_angular = false;
  TwistMeasurement t;
  t.stamp_s = 2.0;
  t.linear_mps << 10.0, 0.1, -0.2;
  t.covariance = Matrix6d::Identity() * 0.01;
  t.mask[1] = false;
  const auto m = makeTwistMeasurement(t, o);
  ASSERT_TRUE(m.ok()) << m.error();
  ASSERT_EQ(m->size, 2);
  EXPECT_EQ(m->indices[0], kStateVx);
  EXPECT_EQ(m->indices[1], kStateVz);
  EXPECT_DOUBLE_EQ(m->z(1), -0.2);
  o.twist_use_linear = false;
  EXPECT_FALSE(makeTwistMeasurement(t, o).ok());  // nothing left to fuse
}

TEST(EkfMeasurement, ScaledTwistModelAndJacobian) {
  // The INS reads (1 + s) v: h = (1 + s) v on the linear rows, the rates unscaled; the Jacobian
  // matches finite differences in every state.
  EkfOptions o;
  TwistMeasurement t;
  t.stamp_s = 2.0;
  t.linear_mps << 12.0, 0.3, -0.1;
  t.angular_radps << 0.01, -0.02, 0.3;
  t.covariance = Matrix6d::Identity() * 1e-4;
  auto m = makeTwistMeasurement(t, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kScaledTwist);
  ASSERT_EQ(m->size, 6);
  StateVector x = StateVector::Zero();
  x.segment<3>(kStateVx) << 11.9, 0.25, -0.05;
  x.segment<3>(kStateWx) << 0.02, -0.01, 0.28;
  x(kStateTwistScale) = 0.004;
  MeasurementVector h;
  MeasurementJacobian jac;
  evaluateMeasurement(*m, x, o.gravity_mps2, &h, &jac);
  EXPECT_NEAR(h(0), 1.004 * 11.9, 1e-12);
  EXPECT_NEAR(h(2), 1.004 * -0.05, 1e-12);
  EXPECT_NEAR(h(5), 0.28, 1e-12);
  EXPECT_NEAR(jac(0, kStateTwistScale), 11.9, 1e-12);
  EXPECT_NEAR(jac(0, kStateVx), 1.004, 1e-12);
  EXPECT_EQ(jac(5, kStateTwistScale), 0.0);
  expectJacobianMatchesNumeric(*m, x, o.gravity_mps2, jac);
  // Off: the direct model, the scale never enters.
  o.estimate_twist_scale = false;
  m = makeTwistMeasurement(t, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kDirect);
  evaluateMeasurement(*m, x, o.gravity_mps2, &h, &jac);
  EXPECT_DOUBLE_EQ(h(0), 11.9);
  EXPECT_EQ(jac.col(kStateTwistScale).cwiseAbs().maxCoeff(), 0.0);
}

TEST(EkfMeasurement, BiasedGnssPositionModelAndJacobian) {
  // A fix reads p + b horizontally and z as is; the Jacobian matches finite differences.
  EkfOptions o;
  PositionMeasurement p;
  p.stamp_s = 3.0;
  p.position_m << 10.0, -4.0, 2.0;
  p.covariance = Eigen::Matrix3d::Identity() * 1.5;
  p.use_z = true;
  auto m = makePositionMeasurement(p, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kBiasedPosition);
  ASSERT_EQ(m->size, 3);
  StateVector x = StateVector::Zero();
  x.head<3>() << 9.0, -3.5, 1.8;
  x(kStateGnssBiasX) = 0.7;
  x(kStateGnssBiasY) = -0.4;
  MeasurementVector h;
  MeasurementJacobian jac;
  evaluateMeasurement(*m, x, o.gravity_mps2, &h, &jac);
  EXPECT_NEAR(h(0), 9.7, 1e-12);
  EXPECT_NEAR(h(1), -3.9, 1e-12);
  EXPECT_NEAR(h(2), 1.8, 1e-12);
  EXPECT_EQ(jac(0, kStateGnssBiasX), 1.0);
  EXPECT_EQ(jac(0, kStateGnssBiasY), 0.0);
  EXPECT_EQ(jac(1, kStateGnssBiasY), 1.0);
  EXPECT_EQ(jac(2, kStateGnssBiasX), 0.0);
  expectJacobianMatchesNumeric(*m, x, o.gravity_mps2, jac);
  // Off: the fix reads the position, the bias never enters.
  o.estimate_gnss_bias = false;
  m = makePositionMeasurement(p, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kDirect);
  evaluateMeasurement(*m, x, o.gravity_mps2, &h, &jac);
  EXPECT_DOUBLE_EQ(h(0), 9.0);
  EXPECT_EQ(jac.block(0, kStateGnssBiasX, 3, 2).cwiseAbs().maxCoeff(), 0.0);
}

TEST(EkfMeasurement, BiasedGyroRateModelAndJacobian) {
  // The gyro reads w + g per axis; the Jacobian matches finite differences.
  EkfOptions o;
  ImuMeasurement imu;
  imu.stamp_s = 1.0;
  imu.has_angular_velocity = true;
  imu.angular_velocity_radps << 0.01, -0.02, 0.3;
  imu.angular_velocity_covariance = Eigen::Matrix3d::Identity() * 1e-6;
  auto m = makeImuAngularVelocityMeasurement(imu, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kBiasedRate);
  StateVector x = StateVector::Zero();
  x.segment<3>(kStateWx) << 0.011, -0.019, 0.29;
  x.segment<3>(kStateGyroBiasX) << 0.0005, -0.0003, 0.0007;
  MeasurementVector h;
  MeasurementJacobian jac;
  evaluateMeasurement(*m, x, o.gravity_mps2, &h, &jac);
  EXPECT_NEAR(h(2), 0.2907, 1e-12);
  EXPECT_EQ(jac(2, kStateGyroBiasZ), 1.0);
  EXPECT_EQ(jac(2, kStateGyroBiasX), 0.0);
  expectJacobianMatchesNumeric(*m, x, o.gravity_mps2, jac);
  // Off: the rates are read as they are.
  o.estimate_gyro_bias = false;
  m = makeImuAngularVelocityMeasurement(imu, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kDirect);
}

TEST(EkfMeasurement, ImuOrientationIgnoresYaw) {
  EkfOptions o;
  ImuMeasurement imu;
  imu.stamp_s = 1.0;
  imu.has_orientation = true;
  imu.orientation = Eigen::Quaterniond(rotationFromRpy(0.05, -0.03, 2.0));
  imu.orientation_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  imu.orientation_covariance(2, 2) = kNaN;  // yaw variance unknown: must not matter
  const auto m = makeImuOrientationMeasurement(imu, o);
  ASSERT_TRUE(m.ok()) << m.error();
  ASSERT_EQ(m->size, 2);
  EXPECT_NEAR(m->z(0), 0.05, 1e-12);
  EXPECT_NEAR(m->z(1), -0.03, 1e-12);
}

TEST(EkfMeasurement, GravityRemovalBothWays) {
  // A tilted vehicle at rest: the accelerometer reads R^T (0, 0, g), the body acceleration is 0.
  EkfOptions o;
  const Eigen::Matrix3d r = rotationFromRpy(0.1, -0.2, 1.0);
  ImuMeasurement imu;
  imu.stamp_s = 1.0;
  imu.has_orientation = true;
  imu.orientation = Eigen::Quaterniond(r);
  imu.has_linear_acceleration = true;
  imu.linear_acceleration_mps2 = r.transpose() * Eigen::Vector3d(0, 0, o.gravity_mps2);
  imu.linear_acceleration_covariance = Eigen::Matrix3d::Identity() * 0.01;

  o.imu_gravity_removal = GravityRemoval::kMeasuredOrientation;
  imu.orientation_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  auto m = makeImuAccelerationMeasurement(imu, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_LT(m->z.norm(), 1e-12);
  // The tilt uncertainty (0.01 rad on roll and pitch) leaks into a through the gravity term:
  // var(f_z) grows by g^2 1e-4 ((sin r cos p)^2 + (cos r sin p)^2), var(f_x) by (g cos p)^2 1e-4.
  const double g2 = o.gravity_mps2 * o.gravity_mps2;
  const double sr = std::sin(0.1), cr = std::cos(0.1), sp = std::sin(-0.2), cp = std::cos(-0.2);
  EXPECT_NEAR(m->R(0, 0), 0.01 + g2 * 1e-4 * cp * cp, 1e-12);
  EXPECT_NEAR(m->R(2, 2), 0.01 + g2 * 1e-4 * (sr * cp * sr * cp + cr * sp * cr * sp), 1e-12);
  imu.orientation_covariance(0, 0) = kNaN;
  EXPECT_FALSE(makeImuAccelerationMeasurement(imu, o).ok());
  imu.orientation_covariance(0, 0) = 1e-4;

  o.imu_gravity_removal = GravityRemoval::kStateEstimate;
  m = makeImuAccelerationMeasurement(imu, o);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->model, MeasurementModel::kAccelerationMinusGravity);
  StateVector x = StateVector::Zero();
  x(kStateRoll) = 0.1;
  x(kStatePitch) = -0.2;
  x(kStateYaw) = -2.0;  // yaw does not matter
  x(kStateAx) = 0.3;
  MeasurementVector h;
  MeasurementJacobian jac;
  evaluateMeasurement(*m, x, o.gravity_mps2, &h, &jac);
  EXPECT_LT((h - imu.linear_acceleration_mps2 - Eigen::Vector3d(0.3, 0, 0)).norm(), 1e-12);
  // Jacobian: identity on a, finite differences on roll and pitch, nothing else.
  expectJacobianMatchesNumeric(*m, x, o.gravity_mps2, jac);
  EXPECT_DOUBLE_EQ(jac(0, kStateAx), 1.0);
  EXPECT_NE(jac(1, kStateRoll), 0.0);

  imu.has_orientation = false;
  o.imu_gravity_removal = GravityRemoval::kMeasuredOrientation;
  EXPECT_FALSE(makeImuAccelerationMeasurement(imu, o).ok());
}

TEST(EkfMeasurement, DifferentialTwistFromOdometryPoses) {
  Eigen::Isometry3d prev = Eigen::Isometry3d::Identity();
  prev.linear() = rotationFromRpy(0.0, 0.0, 1.0);
  prev.translation() << 100.0, 50.0, 2.0;
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.linear() = rotationFromRpy(0.0, 0.0, 0.02);
  step.translation() << 1.0, 0.01, 0.0;
  const auto t = twistFromOdometryIncrement(prev, 10.0, prev * step, 10.1, Matrix6d::Identity());
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_NEAR(t->linear_mps.x(), 10.0, 1e-9);
  EXPECT_NEAR(t->linear_mps.y(), 0.1, 1e-9);
  EXPECT_NEAR(t->angular_radps.z(), 0.2, 1e-9);
  EXPECT_DOUBLE_EQ(t->stamp_s, 10.1);
  EXPECT_FALSE(twistFromOdometryIncrement(prev, 10.0, prev, 10.0, Matrix6d::Identity()).ok());
}

}  // namespace
}  // namespace gmm_localization
