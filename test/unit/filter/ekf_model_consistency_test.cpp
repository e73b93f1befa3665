// The EKF machinery against truth drawn from its own model: x_k+1 = f(x_k, dt) + w_k with
// w_k ~ N(0, diag(q) dt), and every measurement drawn from its stated covariance. Here the EKF is
// the right filter, so the full-state NEES must average the state dimension (16). This checks
// the Jacobians, the Joseph update, angle wrapping, gravity removal, the scaled INS twist
// (z = (1 + s) v with the truth's own scale error s) and delayed insertion together, independently
// of how well the default tuning fits a real car (ekf_simulation_test covers that).
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gmm_localization/core/filter/ekf.h"
#include "gmm_localization/core/filter/ekf_process_model.h"

namespace gmm_localization {
namespace {

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}

// Runs one 20 s drive (IMU and twist at 100 Hz, 6-DOF poses at 5 Hz delivered 100 ms late)
// and appends the full-state NEES every 0.1 s after 2 s.
void runOnce(const EkfOptions& o, unsigned seed, std::vector<double>* nees) {
  const double dt = 0.01, duration = 20.0;
  const double tilt_sigma = 0.005, gyro_sigma = 0.002, accel_sigma = 0.05, v_sigma = 0.05,
               w_sigma = 0.005, pos_sigma = 0.2, ang_sigma = 0.01;
  std::mt19937 rng(100 + seed);
  std::normal_distribution<double> n(0.0, 1.0);
  auto noise = [&](int size) {
    Eigen::VectorXd v(size);
    for (int i = 0; i < size; ++i) v(i) = n(rng);
    return v;
  };
  auto created = Ekf::create(o);
  ASSERT_TRUE(created.ok()) << created.error();
  Ekf f = std::move(created).value();
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.linear() = rotationFromRpy(0.0, 0.0, 0.5);
  const Matrix6d pose_cov(Eigen::Map<const Vector6d>(o.initial_variance.data()).asDiagonal());
  ASSERT_TRUE(f.reset(start, pose_cov, 0.0).ok());
  // Truth starts at a draw from the filter's prior (speed sigma 10 m/s: a moving vehicle).
  StateVector x = f.state().x;
  for (int i = 0; i < kStateSize; ++i) x(i) += std::sqrt(f.state().P(i, i)) * n(rng);
  std::vector<std::pair<PoseMeasurement, double>> pending;  // (pose, arrival time)
  for (int k = 1; k <= static_cast<int>(duration / dt); ++k) {
    const double t = k * dt;
    x = predictStep(x, dt, nullptr);
    for (int i = 0; i < kTunedStateCount; ++i)
      x(i) += std::sqrt(o.process_noise_density[i] * dt) * n(rng);
    // The GNSS bias: its Gauss-Markov step (no fixes here: unobserved, it must stay consistent);
    // the gyro bias: its random walk.
    const double decay = std::exp(-dt / o.gnss_bias_tau_s);
    for (int i = kStateGnssBiasX; i <= kStateGnssBiasY; ++i) {
      x(i) = decay * x(i) + std::sqrt(1.0 - decay * decay) * o.gnss_bias_sigma_m * n(rng);
    }
    for (int i = kStateGyroBiasX; i <= kStateGyroBiasZ; ++i) {
      x(i) += std::sqrt(o.gyro_bias_random_walk * dt) * n(rng);
    }
    for (int i = kStateRoll; i <= kStateYaw; ++i) x(i) = wrapAngle(x(i));
    ImuMeasurement imu;
    imu.stamp_s = t;
    imu.has_orientation = imu.has_angular_velocity = imu.has_linear_acceleration = true;
    const Eigen::Vector3d tilt = tilt_sigma * noise(3);
    imu.orientation = Eigen::Quaterniond(
        rotationFromRpy(x(kStateRoll) + tilt.x(), x(kStatePitch) + tilt.y(), x(kStateYaw) + 2.0));
    imu.orientation_covariance = Eigen::Matrix3d::Identity() * tilt_sigma * tilt_sigma;
    imu.angular_velocity_radps =
        x.segment<3>(kStateWx) + x.segment<3>(kStateGyroBiasX) + gyro_sigma * noise(3);
    imu.angular_velocity_covariance = Eigen::Matrix3d::Identity() * gyro_sigma * gyro_sigma;
    const Eigen::Matrix3d r = rotationFromRpy(x(kStateRoll), x(kStatePitch), x(kStateYaw));
    imu.linear_acceleration_mps2 = x.segment<3>(kStateAx) +
                                   r.transpose() * Eigen::Vector3d(0, 0, o.gravity_mps2) +
                                   accel_sigma * noise(3);
    imu.linear_acceleration_covariance = Eigen::Matrix3d::Identity() * accel_sigma * accel_sigma;
    f.processImu(imu);
    TwistMeasurement tw;
    tw.stamp_s = t;
    tw.linear_mps = (1.0 + x(kStateTwistScale)) * x.segment<3>(kStateVx) + v_sigma * noise(3);
    tw.angular_radps = x.segment<3>(kStateWx) + w_sigma * noise(3);
    tw.covariance.diagonal() << Eigen::Vector3d::Constant(v_sigma * v_sigma),
        Eigen::Vector3d::Constant(w_sigma * w_sigma);
    f.processTwist(tw);
    if (k % 20 == 0) {
      Matrix6d c = Matrix6d::Zero();
      c.diagonal() << Eigen::Vector3d::Constant(pos_sigma * pos_sigma),
          Eigen::Vector3d::Constant(ang_sigma * ang_sigma);
      const Vector6d e = c.cwiseSqrt() * Vector6d(noise(6));
      Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
      m.translation() = x.head<3>() + e.head<3>();
      m.linear() =
          rotationFromRpy(x(kStateRoll) + e(3), x(kStatePitch) + e(4), x(kStateYaw) + e(5));
      pending.emplace_back(PoseMeasurement::full(t, m, c), t + 0.1);  // 100 ms late
    }
    for (auto it = pending.begin(); it != pending.end();) {
      if (it->second <= t + 1e-9) {
        EXPECT_NE(f.processPose(it->first).outcome, FuseOutcome::kRejectedTooOld);
        it = pending.erase(it);
      } else {
        ++it;
      }
    }
    if (k % 10 != 0 || t < 2.0) continue;
    StateVector e = f.state().x - x;
    for (int i = kStateRoll; i <= kStateYaw; ++i) e(i) = wrapAngle(e(i));
    nees->push_back(e.dot(f.state().P.ldlt().solve(e)));
  }
}

TEST(EkfModelConsistency, FullStateNeesMatchesItsDimension) {
  EkfOptions o;
  o.process_noise_density = {1e-4, 1e-4, 1e-4, 1e-6, 1e-6, 1e-6, 1e-3, 1e-3,
                             1e-3, 1e-4, 1e-4, 1e-3, 0.1,  0.1,  0.1,  1e-6};
  o.initial_variance = {1.0, 1.0,  1.0,  1e-4, 1e-4, 1e-3, 1.0, 1.0,
                        1.0, 1e-3, 1e-3, 1e-3, 0.1,  0.1,  0.1, 1e-4};
  o.initial_variance[kStateVx] = 100.0;  // truth speeds drawn with sigma 10 m/s
  o.imu_gravity_removal = GravityRemoval::kStateEstimate;
  std::vector<double> nees;
  for (unsigned seed = 1; seed <= 5; ++seed) runOnce(o, seed, &nees);
  const double anees = mean(nees);
  std::printf(
      "truth from the model, gravity from the state: ANEES(%d states) = %.2f over %zu "
      "samples\n",
      kStateSize, anees, nees.size());
  EXPECT_GT(anees, kStateSize * 0.8);
  EXPECT_LT(anees, kStateSize * 1.2);

  // Gravity removed with the message's orientation (its tilt covariance propagated).
  o.imu_gravity_removal = GravityRemoval::kMeasuredOrientation;
  nees.clear();
  for (unsigned seed = 1; seed <= 5; ++seed) runOnce(o, seed, &nees);
  const double anees_measured = mean(nees);
  std::printf("truth from the model, gravity from the IMU orientation: ANEES = %.2f\n",
              anees_measured);
  EXPECT_GT(anees_measured, kStateSize * 0.8);
  EXPECT_LT(anees_measured, kStateSize * 1.2);
}

}  // namespace
}  // namespace gmm_localization
