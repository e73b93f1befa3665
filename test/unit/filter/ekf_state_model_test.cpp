// EKF state helpers, process model (Jacobian against finite differences, kinematics against
// closed forms) and chi-square gating quantities.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/filter/ekf_gating.h"
#include "gmm_localization/core/filter/ekf_process_model.h"
#include "gmm_localization/core/filter/ekf_state.h"

namespace gmm_localization {
namespace {

TEST(EkfState, WrapAngleRange) {
  for (double a = -20.0; a <= 20.0; a += 0.173) {
    const double w = wrapAngle(a);
    EXPECT_GE(w, -M_PI);
    EXPECT_LT(w, M_PI);
    EXPECT_NEAR(std::remainder(a - w, 2.0 * M_PI), 0.0, 1e-12) << a;
  }
  EXPECT_DOUBLE_EQ(wrapAngle(M_PI), -M_PI);
  EXPECT_TRUE(std::isnan(wrapAngle(NAN)));
}

TEST(EkfState, RpyRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ang(-3.1, 3.1), pitch(-1.5, 1.5);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d rpy(ang(rng), pitch(rng), ang(rng));
    const Eigen::Vector3d back = rpyFromRotation(rotationFromRpy(rpy.x(), rpy.y(), rpy.z()));
    EXPECT_LT((back - rpy).cwiseAbs().maxCoeff(), 1e-9) << rpy.transpose();
  }
}

TEST(EkfState, PoseRoundTrip) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotationFromRpy(0.1, -0.2, 2.5);
  t.translation() = Eigen::Vector3d(10.0, -4.0, 1.5);
  EkfState s;
  setPoseInState(t, &s.x);
  EXPECT_TRUE(s.pose().isApprox(t, 1e-12));
  EXPECT_NEAR(s.x(kStateYaw), 2.5, 1e-12);
}

StateVector randomState(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  StateVector x;
  for (int i = 0; i < kStateSize; ++i) x(i) = u(rng);
  x.segment<3>(kPositionBlock) *= 50.0;
  x.segment<3>(kLinearVelocityBlock) *= 15.0;
  x.segment<3>(kLinearAccelerationBlock) *= 3.0;
  return x;
}

TEST(EkfProcessModel, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    const StateVector x = randomState(rng);
    const double dt = 0.05;
    StateCovariance f;
    predictStep(x, dt, &f);
    constexpr double h = 1e-6;
    for (int j = 0; j < kStateSize; ++j) {
      StateVector xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      StateVector d = predictStep(xp, dt, nullptr) - predictStep(xm, dt, nullptr);
      for (int i = kStateRoll; i <= kStateYaw; ++i) d(i) = wrapAngle(d(i));
      const StateVector numeric = d / (2.0 * h);
      for (int i = 0; i < kStateSize; ++i) {
        EXPECT_NEAR(f(i, j), numeric(i), 1e-6 * (1.0 + std::abs(numeric(i))))
            << "d " << stateName(i) << " / d " << stateName(j) << " trial " << trial;
      }
    }
  }
}

TEST(EkfProcessModel, ConstantTurnFollowsTheCircle) {
  // 10 m/s with a 0.2 rad/s yaw rate: a 50 m radius circle; the body acceleration is the
  // centripetal 2 m/s^2 to the left and the body velocity must stay (10, 0, 0).
  EkfState s;
  s.x.setZero();
  s.x(kStateVx) = 10.0;
  s.x(kStateWz) = 0.2;
  s.x(kStateAy) = 2.0;
  s.P = StateCovariance::Identity() * 1e-4;
  std::array<double, kTunedStateCount> q{};
  predictState(&s, 5.0, q, 0.001);
  const double yaw = 1.0, radius = 50.0;
  EXPECT_NEAR(s.x(kStateYaw), yaw, 1e-9);
  EXPECT_NEAR(s.x(kStateX), radius * std::sin(yaw), 0.02);
  EXPECT_NEAR(s.x(kStateY), radius * (1.0 - std::cos(yaw)), 0.02);
  EXPECT_NEAR(s.x(kStateVx), 10.0, 1e-6);
  EXPECT_NEAR(s.x(kStateVy), 0.0, 1e-6);
}

TEST(EkfProcessModel, StraightAccelerationAndPitchedClimb) {
  EkfState s;
  s.x.setZero();
  s.x(kStatePitch) = -0.1;  // nose up (ZYX pitch about +y tips +x downwards for positive pitch)
  s.x(kStateVx) = 5.0;
  s.x(kStateAx) = 1.0;
  std::array<double, kTunedStateCount> q{};
  predictState(&s, 2.0, q, 0.01);
  const double distance = 5.0 * 2.0 + 0.5 * 1.0 * 4.0;
  EXPECT_NEAR(s.x(kStateX), distance * std::cos(0.1), 1e-9);
  EXPECT_NEAR(s.x(kStateZ), distance * std::sin(0.1), 1e-9);
  EXPECT_NEAR(s.x(kStateVx), 7.0, 1e-12);
}

TEST(EkfProcessModel, CovarianceGrowsByTheSpectralDensityAndStaysSymmetric) {
  EkfState s;
  s.x.setZero();
  s.P = StateCovariance::Identity() * 0.01;
  std::array<double, kTunedStateCount> q{};
  q.fill(0.0);
  q[kStateAx] = 2.0;
  q[kStateYaw] = 0.5;
  predictState(&s, 1.0, q, 0.02);
  EXPECT_NEAR(s.P(kStateAx, kStateAx), 0.01 + 2.0, 1e-9);
  // yaw(t) = yaw0 + wz t: var = var_yaw + var_wz t^2 + q_yaw t.
  EXPECT_NEAR(s.P(kStateYaw, kStateYaw), 0.01 + 0.01 + 0.5, 1e-9);
  EXPECT_GT(s.P(kStateVx, kStateVx), 0.01 + 0.5);  // acceleration noise feeds velocity
  EXPECT_EQ((s.P - s.P.transpose()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_DOUBLE_EQ(s.time_s, 1.0);
}

TEST(EkfProcessModel, GnssBiasIsAGaussMarkovProcessAtItsStationaryVariance) {
  EkfState s;
  s.x.setZero();
  s.x(kStateGnssBiasX) = 2.0;
  s.x(kStateGnssBiasY) = -1.0;
  s.P = StateCovariance::Identity() * 0.01;
  s.P(kStateGnssBiasX, kStateGnssBiasX) = 1.5 * 1.5;  // at the stationary variance
  s.P(kStateGnssBiasY, kStateGnssBiasY) = 0.0;        // known exactly at first
  const std::array<double, kTunedStateCount> q{};
  CalibrationProcess bias;
  bias.gnss_bias_sigma_m = 1.5;
  bias.gnss_bias_tau_s = 60.0;
  predictState(&s, 30.0, q, 0.02, bias);
  const double e = std::exp(-0.5);
  EXPECT_NEAR(s.x(kStateGnssBiasX), 2.0 * e, 1e-9);
  EXPECT_NEAR(s.x(kStateGnssBiasY), -1.0 * e, 1e-9);
  EXPECT_NEAR(s.P(kStateGnssBiasX, kStateGnssBiasX), 1.5 * 1.5, 1e-9);  // stays there
  EXPECT_NEAR(s.P(kStateGnssBiasY, kStateGnssBiasY), 1.5 * 1.5 * (1.0 - e * e), 1e-9);
  EXPECT_EQ(s.P(kStateGnssBiasX, kStateX), 0.0);  // not coupled by the motion
  // tau = 0: held, with its variance.
  const StateVector before = s.x;
  const double var_before = s.P(kStateGnssBiasX, kStateGnssBiasX);
  predictState(&s, 40.0, q, 0.02);
  EXPECT_EQ(s.x(kStateGnssBiasX), before(kStateGnssBiasX));
  EXPECT_EQ(s.P(kStateGnssBiasX, kStateGnssBiasX), var_before);
}

TEST(EkfGating, ChiSquareQuantilesMatchTables) {
  // Reference values from scipy.stats.chi2.ppf.
  EXPECT_NEAR(chiSquareQuantile(0.95, 1), 3.841458820694124, 1e-7);
  EXPECT_NEAR(chiSquareQuantile(0.99, 2), 9.21034037197618, 1e-7);
  EXPECT_NEAR(chiSquareQuantile(0.999, 3), 16.26623619623813, 1e-6);
  EXPECT_NEAR(chiSquareQuantile(0.9999, 3), 21.107513466160444, 1e-6);
  EXPECT_NEAR(chiSquareQuantile(0.9999, 6), 27.85634123601417, 1e-6);
  EXPECT_NEAR(chiSquareQuantile(0.999999, 3), 30.66484970615427, 1e-5);
  EXPECT_NEAR(chiSquareQuantile(0.5, 5), 4.351460191095526, 1e-7);
  EXPECT_TRUE(std::isinf(chiSquareQuantile(1.0, 3)));
  EXPECT_NEAR(chiSquareUpperTail(50.0, 4), 3.610865404890647e-10, 1e-19);
  EXPECT_NEAR(chiSquareUpperTail(30.0, 5), 1.4748581038443073e-05, 1e-13);
  EXPECT_DOUBLE_EQ(chiSquareUpperTail(0.0, 3), 1.0);
}

}  // namespace
}  // namespace gmm_localization
