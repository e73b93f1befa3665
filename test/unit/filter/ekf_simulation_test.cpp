// The EKF against synthetic ground truth: a vehicle driving curves with changing speed over
// gently rolling and pitching ground, noisy IMU and INS twist at 100 Hz, and noisy scan-match
// poses (full x, y, yaw covariance) at 5 Hz that arrive 50-150 ms late. Checks consistency
// (NEES), accuracy, covariance health, late-vs-in-order equivalence, and the growth of the
// uncertainty without scan matches. Fixed seeds; every number printed is what was measured.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "gmm_localization/core/filter/ekf.h"

namespace gmm_localization {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kGravity = 9.80665;

// ---- Ground truth: analytic attitude and speed, position integrated with RK4 at 1 ms ----------

struct TruthSample {
  Eigen::Vector3d position, rpy, w_body, a_body, v_body;
};

class Trajectory {
 public:
  explicit Trajectory(double duration_s) {
    const int n = static_cast<int>(std::lround(duration_s / kStep)) + 1;
    positions_.resize(n);
    positions_[0] = Eigen::Vector3d(20.0, -10.0, 3.0);
    for (int i = 1; i < n; ++i) {
      const double t = (i - 1) * kStep;
      const Eigen::Vector3d k1 = velocityMap(t), k2 = velocityMap(t + 0.5 * kStep),
                            k4 = velocityMap(t + kStep);
      positions_[i] = positions_[i - 1] + kStep / 6.0 * (k1 + 4.0 * k2 + k4);
    }
  }

  // Truth at a time on the 1 ms grid.
  TruthSample at(double t) const {
    TruthSample s;
    const int i = static_cast<int>(std::lround(t / kStep));
    s.position = positions_.at(i);
    s.rpy = Eigen::Vector3d(roll(t), pitch(t), yaw(t));
    const double r = roll(t), p = pitch(t), yd = yawRate(t), rd = rollRate(t), pd = pitchRate(t);
    s.w_body =
        Eigen::Vector3d(rd - std::sin(p) * yd, std::cos(r) * pd + std::sin(r) * std::cos(p) * yd,
                        -std::sin(r) * pd + std::cos(r) * std::cos(p) * yd);
    s.v_body = Eigen::Vector3d(speed(t), 0.0, 0.0);
    s.a_body = Eigen::Vector3d(speedRate(t), 0.0, 0.0) + s.w_body.cross(s.v_body);
    return s;
  }

 private:
  static constexpr double kStep = 0.001;
  static double speed(double t) { return 10.0 + 3.0 * std::sin(kTwoPi * t / 12.0); }
  static double speedRate(double t) { return 3.0 * kTwoPi / 12.0 * std::cos(kTwoPi * t / 12.0); }
  static double yawRate(double t) {
    return 0.15 * std::sin(kTwoPi * t / 20.0) + 0.08 * std::sin(kTwoPi * t / 7.0 + 1.0);
  }
  static double yaw(double t) {  // integral of yawRate from 0, plus 2.9 rad: crosses +-pi
    return 2.9 + 0.15 * 20.0 / kTwoPi * (1.0 - std::cos(kTwoPi * t / 20.0)) +
           0.08 * 7.0 / kTwoPi * (std::cos(1.0) - std::cos(kTwoPi * t / 7.0 + 1.0));
  }
  static double roll(double t) { return 0.02 * std::sin(kTwoPi * t / 5.0); }
  static double rollRate(double t) { return 0.02 * kTwoPi / 5.0 * std::cos(kTwoPi * t / 5.0); }
  static double pitch(double t) { return 0.03 * std::sin(kTwoPi * t / 15.0); }
  static double pitchRate(double t) { return 0.03 * kTwoPi / 15.0 * std::cos(kTwoPi * t / 15.0); }
  static Eigen::Vector3d velocityMap(double t) {
    return rotationFromRpy(roll(t), pitch(t), wrapAngle(yaw(t))) * Eigen::Vector3d(speed(t), 0, 0);
  }
  std::vector<Eigen::Vector3d> positions_;
};

// ---- Sensors ----------------------------------------------------------------------------------

struct Event {
  double arrival_s;
  int kind;  // 0 imu, 1 twist, 2 pose
  int index;
};

struct SensorLog {
  std::vector<ImuMeasurement> imu;
  std::vector<TwistMeasurement> twist;
  std::vector<PoseMeasurement> pose;
  std::vector<Event> events;  // in arrival order
};

SensorLog simulateSensors(const Trajectory& truth, double duration_s, bool with_poses,
                          double max_delay_s, unsigned seed,
                          const Eigen::Vector3d& gyro_bias = Eigen::Vector3d::Zero()) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SensorLog log;
  const double gyro_sigma = 0.002, accel_sigma = 0.05, tilt_sigma = 0.005;
  const double v_sigma = 0.05, w_sigma = 0.005;
  const int steps = static_cast<int>(std::lround(duration_s / 0.01));
  for (int k = 1; k < steps; ++k) {
    const double t = k * 0.01;
    const TruthSample s = truth.at(t);
    ImuMeasurement imu;
    imu.stamp_s = t;
    imu.has_orientation = imu.has_angular_velocity = imu.has_linear_acceleration = true;
    // The IMU's yaw is relative (an arbitrary, drifting offset): the filter must ignore it.
    imu.orientation = Eigen::Quaterniond(rotationFromRpy(s.rpy.x() + tilt_sigma * n(rng),
                                                         s.rpy.y() + tilt_sigma * n(rng),
                                                         s.rpy.z() + 1.0 + 0.01 * t));
    imu.orientation_covariance = Eigen::Matrix3d::Identity() * tilt_sigma * tilt_sigma;
    imu.angular_velocity_radps =
        s.w_body + gyro_bias + gyro_sigma * Eigen::Vector3d(n(rng), n(rng), n(rng));
    imu.angular_velocity_covariance = Eigen::Matrix3d::Identity() * gyro_sigma * gyro_sigma;
    const Eigen::Matrix3d r = rotationFromRpy(s.rpy.x(), s.rpy.y(), s.rpy.z());
    imu.linear_acceleration_mps2 = s.a_body + r.transpose() * Eigen::Vector3d(0, 0, kGravity) +
                                   accel_sigma * Eigen::Vector3d(n(rng), n(rng), n(rng));
    imu.linear_acceleration_covariance = Eigen::Matrix3d::Identity() * accel_sigma * accel_sigma;
    log.events.push_back({t, 0, static_cast<int>(log.imu.size())});
    log.imu.push_back(imu);

    TwistMeasurement tw;
    tw.stamp_s = t + 0.005;  // the INS runs on its own 100 Hz grid, offset from the IMU
    const TruthSample st = truth.at(tw.stamp_s);
    tw.linear_mps = st.v_body + v_sigma * Eigen::Vector3d(n(rng), n(rng), n(rng));
    tw.angular_radps = st.w_body + w_sigma * Eigen::Vector3d(n(rng), n(rng), n(rng));
    tw.covariance.setZero();
    tw.covariance.diagonal() << Eigen::Vector3d::Constant(v_sigma * v_sigma),
        Eigen::Vector3d::Constant(w_sigma * w_sigma);
    log.events.push_back({tw.stamp_s, 1, static_cast<int>(log.twist.size())});
    log.twist.push_back(tw);

    if (with_poses && k % 20 == 0) {
      // Scan match: 0.3 m along-track, 0.15 m cross-track, 0.01 rad yaw, cross-track and yaw
      // correlated; stamped 3 ms after the IMU sample, delivered 50 ms to max_delay_s later.
      const double ts = t + 0.003;
      const TruthSample sp = truth.at(ts);
      Eigen::Matrix3d c_vehicle;
      c_vehicle << 0.09, 0.0, 0.0, 0.0, 0.0225, 0.3 * 0.15 * 0.01, 0.0, 0.3 * 0.15 * 0.01, 1e-4;
      Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
      rot.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(sp.rpy.z()).toRotationMatrix();
      const Eigen::Matrix3d c = rot * c_vehicle * rot.transpose();
      const Eigen::Vector3d e =
          Eigen::LLT<Eigen::Matrix3d>(c).matrixL() * Eigen::Vector3d(n(rng), n(rng), n(rng));
      log.pose.push_back(PoseMeasurement::planar(
          ts, sp.position.x() + e.x(), sp.position.y() + e.y(), wrapAngle(sp.rpy.z() + e.z()), c));
      // Drawn in every case so that runs with and without delay see the same noise.
      const double delay = 0.05 + (max_delay_s - 0.05) * unit(rng);
      const double arrival = max_delay_s > 0.0 ? ts + delay : ts;
      log.events.push_back({arrival, 2, static_cast<int>(log.pose.size()) - 1});
    }
  }
  std::stable_sort(log.events.begin(), log.events.end(),
                   [](const Event& a, const Event& b) { return a.arrival_s < b.arrival_s; });
  return log;
}

// ---- Running the filter -------------------------------------------------------------------------

struct RunStats {
  std::vector<double> nees_xy_yaw;  // 3 dof, one per 0.1 s after warm-up
  std::vector<double> nees_velocity;
  int samples = 0, within_3_sigma = 0;  // all of x, y, yaw within 3 sigma
  double sum_sq_horizontal_error = 0.0, max_horizontal_error_m = 0.0;
  double max_horizontal_sigma_m = 0.0;
  std::vector<std::pair<double, double>> sigma_over_time;  // (t, max horizontal sigma)
  std::vector<double> yaw_errors;                          // after warm-up, one per 0.1 s
  bool covariance_always_spd = true, state_always_finite = true;
  EkfState final_state;
  EkfDiagnostics diagnostics;
};

RunStats run(const Trajectory& truth, const SensorLog& log, unsigned seed, double warmup_s,
             const EkfOptions& options = {}) {
  auto created = Ekf::create(options);
  EXPECT_TRUE(created.ok()) << created.error();
  Ekf f = std::move(created).value();
  // Start from truth perturbed consistently with the stated initial covariance.
  std::mt19937 rng(seed + 1000);
  std::normal_distribution<double> n(0.0, 1.0);
  const TruthSample s0 = truth.at(0.0);
  Vector6d sigma0;
  sigma0 << 0.5, 0.5, 0.1, 0.01, 0.01, 0.05;
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.translation() =
      s0.position + Eigen::Vector3d(sigma0(0) * n(rng), sigma0(1) * n(rng), sigma0(2) * n(rng));
  start.linear() = rotationFromRpy(s0.rpy.x() + sigma0(3) * n(rng), s0.rpy.y() + sigma0(4) * n(rng),
                                   s0.rpy.z() + sigma0(5) * n(rng));
  EXPECT_TRUE(f.reset(start, Matrix6d(sigma0.cwiseAbs2().asDiagonal()), 0.0).ok());

  RunStats stats;
  for (const Event& e : log.events) {
    if (e.kind == 0) {
      f.processImu(log.imu[e.index]);
    } else if (e.kind == 1) {
      f.processTwist(log.twist[e.index]);
    } else {
      f.processPose(log.pose[e.index]);
    }
    if (e.kind != 0 || (e.index + 1) % 10 != 0) continue;  // evaluate every 0.1 s
    const EkfState& s = f.state();
    stats.state_always_finite &= s.x.allFinite() && s.P.allFinite();
    stats.covariance_always_spd &= (s.P - s.P.transpose()).cwiseAbs().maxCoeff() == 0.0 &&
                                   Eigen::LLT<StateCovariance>(s.P).info() == Eigen::Success;
    const TruthSample t = truth.at(s.time_s);
    const double sigma_h = f.diagnostics().max_horizontal_sigma_m;
    stats.sigma_over_time.emplace_back(s.time_s, sigma_h);
    if (s.time_s < warmup_s) continue;
    const int idx[3] = {kStateX, kStateY, kStateYaw};
    Eigen::Vector3d err(s.x(kStateX) - t.position.x(), s.x(kStateY) - t.position.y(),
                        wrapAngle(s.x(kStateYaw) - t.rpy.z()));
    Eigen::Matrix3d p;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) p(a, b) = s.P(idx[a], idx[b]);
    }
    stats.nees_xy_yaw.push_back(err.dot(p.ldlt().solve(err)));
    stats.yaw_errors.push_back(err(2));
    const Eigen::Vector3d ev = s.linearVelocity() - t.v_body;
    stats.nees_velocity.push_back(ev.dot(s.P.block<3, 3>(kStateVx, kStateVx).ldlt().solve(ev)));
    ++stats.samples;
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside &= std::abs(err(a)) <= 3.0 * std::sqrt(p(a, a));
    stats.within_3_sigma += inside;
    const double eh = err.head<2>().norm();
    stats.sum_sq_horizontal_error += eh * eh;
    stats.max_horizontal_error_m = std::max(stats.max_horizontal_error_m, eh);
    stats.max_horizontal_sigma_m = std::max(stats.max_horizontal_sigma_m, sigma_h);
  }
  stats.final_state = f.state();
  stats.diagnostics = f.diagnostics();
  return stats;
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}

constexpr double kDuration = 60.0;
constexpr double kWarmup = 5.0;

TEST(EkfSimulation, ConsistentAndAccurateWithLateScanMatches) {
  const Trajectory truth(kDuration);
  std::vector<double> all_nees, all_nees_v;
  int samples = 0, inside = 0;
  double sum_sq = 0.0;
  std::printf(
      "seed  ANEES(x,y,yaw)  ANEES(v)  in3sigma  rms_h[m]  max_h[m]  max_sigma_h[m]  "
      "pose fused/gated  delayed  replayed\n");
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const SensorLog log = simulateSensors(truth, kDuration, true, 0.15, seed);
    const RunStats r = run(truth, log, seed, kWarmup);
    EXPECT_TRUE(r.state_always_finite) << "seed " << seed;
    EXPECT_TRUE(r.covariance_always_spd) << "seed " << seed;
    const auto& pose = r.diagnostics.source(MeasurementSource::kPose);
    std::printf("%4u  %14.2f  %8.2f  %8.3f  %8.3f  %8.3f  %14.3f  %8lu/%-6lu  %7lu  %8lu\n", seed,
                mean(r.nees_xy_yaw), mean(r.nees_velocity), double(r.within_3_sigma) / r.samples,
                std::sqrt(r.sum_sq_horizontal_error / r.samples), r.max_horizontal_error_m,
                r.max_horizontal_sigma_m, static_cast<unsigned long>(pose.fused),
                static_cast<unsigned long>(pose.rejected_gate),
                static_cast<unsigned long>(r.diagnostics.delayed_measurements),
                static_cast<unsigned long>(r.diagnostics.replayed_measurements));
    all_nees.insert(all_nees.end(), r.nees_xy_yaw.begin(), r.nees_xy_yaw.end());
    all_nees_v.insert(all_nees_v.end(), r.nees_velocity.begin(), r.nees_velocity.end());
    samples += r.samples;
    inside += r.within_3_sigma;
    sum_sq += r.sum_sq_horizontal_error;
    // Every scan match arrived late and was inserted; consistent ones pass the gate.
    EXPECT_EQ(r.diagnostics.delayed_measurements, pose.fused + pose.rejected_gate);
    EXPECT_LE(pose.rejected_gate, 3u) << "seed " << seed;
    EXPECT_GT(pose.fused, 280u) << "seed " << seed;
    EXPECT_LT(r.max_horizontal_sigma_m, 0.5) << "seed " << seed;
  }
  const double anees = mean(all_nees), anees_v = mean(all_nees_v);
  std::printf("all   %14.2f  %8.2f  %8.3f  %8.3f\n", anees, anees_v, double(inside) / samples,
              std::sqrt(sum_sq / samples));
  // A consistent filter has E[NEES] = 3 for (x, y, yaw). Samples 0.1 s apart are strongly
  // correlated, so the band is wider than an i.i.d. chi-square bound would be.
  // Bands: at most 3x conservative and 1.5x overconfident in variance.
  EXPECT_GT(anees, 1.0);
  EXPECT_LT(anees, 4.5);
  EXPECT_GT(anees_v, 1.0);
  EXPECT_LT(anees_v, 4.5);
  EXPECT_GT(double(inside) / samples, 0.95);
  EXPECT_LT(std::sqrt(sum_sq / samples), 0.25);
}

TEST(EkfSimulation, LateOutlierScanMatchesAreGated) {
  const Trajectory truth(kDuration);
  SensorLog log = simulateSensors(truth, kDuration, true, 0.15, 9);
  // Every 50th match lands 10 m off to the side (a wrong lane, a repeated facade).
  int outliers = 0;
  for (std::size_t i = 49; i < log.pose.size(); i += 50, ++outliers) {
    log.pose[i].map_T_base.translation() +=
        log.pose[i].map_T_base.linear() * Eigen::Vector3d(0, 10, 0);
  }
  const RunStats r = run(truth, log, 9, kWarmup);
  const auto& pose = r.diagnostics.source(MeasurementSource::kPose);
  std::printf("outliers injected %d: pose fused %lu, gated %lu, rms_h %.3f m, max_h %.3f m\n",
              outliers, static_cast<unsigned long>(pose.fused),
              static_cast<unsigned long>(pose.rejected_gate),
              std::sqrt(r.sum_sq_horizontal_error / r.samples), r.max_horizontal_error_m);
  EXPECT_EQ(pose.rejected_gate, static_cast<uint64_t>(outliers));
  EXPECT_EQ(pose.fused, log.pose.size() - outliers);
  EXPECT_LT(r.max_horizontal_error_m, 0.3);
}

TEST(EkfSimulation, LateScanMatchesGiveTheSameResultAsInOrderDelivery) {
  const Trajectory truth(20.0);
  const SensorLog late = simulateSensors(truth, 20.0, true, 0.15, 42);
  const SensorLog in_order = simulateSensors(truth, 20.0, true, 0.0, 42);  // same draws
  ASSERT_EQ(late.pose.size(), in_order.pose.size());
  const RunStats a = run(truth, late, 42, kWarmup);
  const RunStats b = run(truth, in_order, 42, kWarmup);
  EXPECT_GT(a.diagnostics.delayed_measurements, 90u);
  EXPECT_EQ(b.diagnostics.delayed_measurements, 0u);
  EXPECT_EQ(a.final_state.time_s, b.final_state.time_s);
  const double dx = (a.final_state.x - b.final_state.x).cwiseAbs().maxCoeff();
  const double dp = (a.final_state.P - b.final_state.P).cwiseAbs().maxCoeff();
  std::printf("late vs in-order after 20 s: max |dx| = %.3g, max |dP| = %.3g\n", dx, dp);
  EXPECT_LT(dx, 1e-9);
  EXPECT_LT(dp, 1e-9);
}

TEST(EkfSimulation, UncertaintyGrowsWithOdometryOnlyAndStaysBoundedWithScanMatches) {
  const Trajectory truth(kDuration);
  const SensorLog odometry = simulateSensors(truth, kDuration, false, 0.15, 7);
  const SensorLog aided = simulateSensors(truth, kDuration, true, 0.15, 7);
  const RunStats o = run(truth, odometry, 7, kWarmup);
  const RunStats a = run(truth, aided, 7, kWarmup);
  auto sigmaAt = [](const RunStats& r, double t) -> double {
    for (const auto& ts : r.sigma_over_time) {
      if (ts.first >= t - 1e-9) return ts.second;
    }
    return NAN;
  };
  std::printf("t[s]   sigma_h odometry-only [m]   sigma_h with scan matches [m]\n");
  for (double t : {1.0, 10.0, 20.0, 30.0, 40.0, 50.0, 59.9}) {
    std::printf("%5.1f   %24.3f   %29.3f\n", t, sigmaAt(o, t), sigmaAt(a, t));
  }
  // Odometry only: grows steadily (no absolute x, y, yaw information).
  for (double t = 10.0; t < 59.0; t += 10.0) {
    EXPECT_GT(sigmaAt(o, t + 10.0 > 59.9 ? 59.9 : t + 10.0), sigmaAt(o, t)) << t;
  }
  EXPECT_GT(sigmaAt(o, 59.9), 2.0 * sigmaAt(o, 10.0));
  EXPECT_GT(sigmaAt(o, 59.9), 5.0 * a.max_horizontal_sigma_m);
  // With scan matches: bounded over the whole run after warm-up.
  EXPECT_LT(a.max_horizontal_sigma_m, 0.5);
  EXPECT_LT(sigmaAt(a, 59.9), 0.5);
  // Odometry-only is still consistent: truth stays inside its (growing) 3 sigma.
  EXPECT_GT(double(o.within_3_sigma) / o.samples, 0.95);
  EXPECT_TRUE(o.covariance_always_spd);
}

TEST(EkfSimulation, AGyroBiasIsCalibratedAgainstTheInsRates) {
  // The IMU's rates carry a constant bias (a few tenths of a mrad/s), the INS twist's do not.
  // With the bias in the state the filter calibrates it and its heading does not lean; taken as
  // unbiased the two rate sources disagree and the heading leans toward the gyro.
  const Trajectory truth(kDuration);
  const Eigen::Vector3d bias(0.0006, -0.0004, 0.0008);
  const SensorLog log = simulateSensors(truth, kDuration, true, 0.15, 21, bias);
  const RunStats with_state = run(truth, log, 21, kWarmup);
  EkfOptions off;
  off.estimate_gyro_bias = false;
  const RunStats without = run(truth, log, 21, kWarmup, off);
  const EkfDiagnostics& d = with_state.diagnostics;
  std::printf(
      "gyro bias (0.6, -0.4, 0.8) mrad/s: estimated (%.3f, %.3f, %.3f) mrad/s, sigma %.3f; mean "
      "heading error %.3f mrad with the state, %.3f mrad without\n",
      1e3 * d.gyro_bias_radps.x(), 1e3 * d.gyro_bias_radps.y(), 1e3 * d.gyro_bias_radps.z(),
      1e3 * d.gyro_bias_sigma_radps, 1e3 * mean(with_state.yaw_errors),
      1e3 * mean(without.yaw_errors));
  EXPECT_LT((d.gyro_bias_radps - bias).norm(), 3.0 * d.gyro_bias_sigma_radps);
  EXPECT_LT(d.gyro_bias_sigma_radps, 0.0002);
  EXPECT_LT(std::abs(mean(with_state.yaw_errors)), 0.5 * std::abs(mean(without.yaw_errors)));
  EXPECT_TRUE(with_state.covariance_always_spd);
}

}  // namespace
}  // namespace gmm_localization
