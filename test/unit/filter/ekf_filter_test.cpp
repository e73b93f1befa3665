// The EKF's contract on simple scenes: options, initialization, gating, invalid input, time
// handling (late, too old, backwards, forward jump), state queries, setPose, bounded history.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "gmm_localization/core/filter/ekf.h"

namespace gmm_localization {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Matrix6d poseCov(double sigma_xy, double sigma_angle) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_xy * sigma_xy,
      sigma_angle * sigma_angle, sigma_angle * sigma_angle, sigma_angle * sigma_angle;
  return c;
}

Ekf makeFilter(const EkfOptions& o = EkfOptions()) {
  auto f = Ekf::create(o);
  EXPECT_TRUE(f.ok()) << f.error();
  return std::move(f).value();
}

TwistMeasurement stillTwist(double t) {
  TwistMeasurement m;
  m.stamp_s = t;
  m.covariance = Matrix6d::Identity() * 1e-4;
  return m;
}

ImuMeasurement levelImu(double t, double gravity) {
  ImuMeasurement m;
  m.stamp_s = t;
  m.has_orientation = m.has_angular_velocity = m.has_linear_acceleration = true;
  m.orientation_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  m.angular_velocity_covariance = Eigen::Matrix3d::Identity() * 1e-5;
  m.linear_acceleration_mps2 = Eigen::Vector3d(0, 0, gravity);
  m.linear_acceleration_covariance = Eigen::Matrix3d::Identity() * 1e-3;
  return m;
}

// Stationary vehicle at the origin, IMU and twist at 100 Hz from t0 to t1 (inclusive).
void feedStill(Ekf* f, double t0, double t1) {
  for (int k = static_cast<int>(std::lround(t0 * 100)); k <= std::lround(t1 * 100); ++k) {
    const double t = k * 0.01;
    f->processImu(levelImu(t, f->options().gravity_mps2));
    f->processTwist(stillTwist(t));
  }
}

bool symmetricPositiveDefinite(const StateCovariance& p) {
  return (p - p.transpose()).cwiseAbs().maxCoeff() == 0.0 &&
         Eigen::LLT<StateCovariance>(p).info() == Eigen::Success;
}

TEST(EkfOptions, ValidateNamesKeyValueAndRange) {
  EkfOptions o;
  EXPECT_TRUE(o.validate().ok()) << o.validate().error();
  o.history_length_s = -1.0;
  Status s = o.validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("history_length_s = -1"), std::string::npos) << s.error();
  EXPECT_NE(s.error().find("(0, 60]"), std::string::npos) << s.error();
  o = EkfOptions();
  o.process_noise_density[kStateRoll] = kNaN;
  s = o.validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("process_noise_density[3] (roll)"), std::string::npos) << s.error();
  o = EkfOptions();
  o.time_backwards_tolerance_s = 1.0;  // shorter than the history
  EXPECT_FALSE(o.validate().ok());
  o = EkfOptions();
  o.pose_gate_probability = 0.0;
  const auto f = Ekf::create(o);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.error().find("pose_gate_probability"), std::string::npos) << f.error();
}

TEST(Ekf, RejectsMeasurementsBeforeInitialization) {
  Ekf f = makeFilter();
  EXPECT_FALSE(f.initialized());
  EXPECT_TRUE(std::isnan(f.time()));
  const FuseReport r = f.processTwist(stillTwist(1.0));
  EXPECT_EQ(r.outcome, FuseOutcome::kRejectedNotInitialized);
  EXPECT_FALSE(r.reason.empty());
  EXPECT_FALSE(f.stateAt(1.0).ok());
}

TEST(Ekf, ImuGivesOneReportPerPresentPart) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.1, 0.01), 0.0).ok());
  auto reports = f.processImu(levelImu(0.01, f.options().gravity_mps2));
  ASSERT_EQ(reports.size(), 3u);
  EXPECT_EQ(reports[0].source, MeasurementSource::kImuOrientation);
  EXPECT_EQ(reports[1].source, MeasurementSource::kImuAngularVelocity);
  EXPECT_EQ(reports[2].source, MeasurementSource::kImuLinearAcceleration);
  for (const auto& r : reports) EXPECT_TRUE(r.fused()) << r.reason;
  ImuMeasurement none;
  none.stamp_s = 0.02;
  EXPECT_TRUE(f.processImu(none).empty());
}

TEST(Ekf, GateRejectsTenMetreOutlierAndAcceptsNormalUpdates) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 0.0).ok());
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.04, 0.04, 1e-4).asDiagonal();
  int accepted = 0;
  for (int k = 1; k <= 50; ++k) {
    const double t = k * 0.2;
    feedStill(&f, t - 0.19, t);
    const FuseReport r =
        f.processPose(PoseMeasurement::planar(t, 0.2 * n(rng), 0.2 * n(rng), 0.01 * n(rng), cov));
    accepted += r.fused();
  }
  EXPECT_EQ(accepted, 50);
  const Eigen::Vector3d before = f.state().x.head<3>();
  const FuseReport outlier = f.processPose(PoseMeasurement::planar(10.0, 10.0, 0.0, 0.0, cov));
  EXPECT_EQ(outlier.outcome, FuseOutcome::kRejectedGate);
  EXPECT_GT(outlier.mahalanobisDistance(), 10.0);
  EXPECT_NEAR(outlier.gate_threshold_sq, 21.1075, 1e-3);  // chi-square(3) at 0.9999
  EXPECT_NE(outlier.reason.find("Mahalanobis distance"), std::string::npos) << outlier.reason;
  EXPECT_LT((f.state().x.head<3>() - before).norm(), 1e-12);
  const auto d = f.diagnostics();
  EXPECT_EQ(d.source(MeasurementSource::kPose).fused, 50u);
  EXPECT_EQ(d.source(MeasurementSource::kPose).rejected_gate, 1u);
  EXPECT_EQ(d.source(MeasurementSource::kPose).consecutive_gate_rejections, 1u);
  EXPECT_GT(d.source(MeasurementSource::kPose).last_mahalanobis_sq, 100.0);
  // The next normal update is accepted again and clears the consecutive count.
  feedStill(&f, 10.01, 10.2);
  EXPECT_TRUE(f.processPose(PoseMeasurement::planar(10.2, 0.05, -0.05, 0.0, cov)).fused());
  EXPECT_EQ(f.diagnostics().source(MeasurementSource::kPose).consecutive_gate_rejections, 0u);
}

TEST(Ekf, NonFiniteInputsNeverReachTheState) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 0.0).ok());
  feedStill(&f, 0.01, 1.0);
  const EkfState before = f.state();

  TwistMeasurement t = stillTwist(1.01);
  t.linear_mps.x() = kNaN;
  EXPECT_EQ(f.processTwist(t).outcome, FuseOutcome::kRejectedInvalid);
  t = stillTwist(1.01);
  t.covariance(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(f.processTwist(t).outcome, FuseOutcome::kRejectedInvalid);
  t = stillTwist(kNaN);
  EXPECT_EQ(f.processTwist(t).outcome, FuseOutcome::kRejectedInvalid);

  ImuMeasurement imu = levelImu(1.01, f.options().gravity_mps2);
  imu.angular_velocity_radps.y() = -std::numeric_limits<double>::infinity();
  imu.linear_acceleration_mps2.z() = kNaN;
  imu.orientation.w() = kNaN;
  for (const FuseReport& r : f.processImu(imu)) {
    EXPECT_EQ(r.outcome, FuseOutcome::kRejectedInvalid) << sourceName(r.source);
    EXPECT_FALSE(r.reason.empty());
  }
  PoseMeasurement p = PoseMeasurement::planar(1.01, kNaN, 0.0, 0.0, Eigen::Matrix3d::Identity());
  const FuseReport pr = f.processPose(p);
  EXPECT_EQ(pr.outcome, FuseOutcome::kRejectedInvalid);
  EXPECT_NE(pr.reason.find("not finite"), std::string::npos) << pr.reason;
  EXPECT_EQ(f.state().time_s, before.time_s);
  EXPECT_TRUE(f.state().x == before.x);
  EXPECT_TRUE(f.state().P == before.P);

  // A huge but finite value is not invalid; it fails the gate (its d^2 overflows to infinity) and
  // only the prediction to its stamp remains.
  p = PoseMeasurement::planar(1.01, 1e300, 0.0, 0.0, Eigen::Matrix3d::Identity());
  const FuseReport huge = f.processPose(p);
  EXPECT_EQ(huge.outcome, FuseOutcome::kRejectedGate) << huge.reason;
  EXPECT_TRUE(f.state().x.allFinite());
  EXPECT_TRUE(f.state().P.allFinite());
  EXPECT_LT(f.state().x.head<3>().norm(), 0.1);
  EXPECT_FALSE(
      f.reset(Eigen::Isometry3d(Eigen::Translation3d(kNaN, 0, 0)), poseCov(1, 1), 2.0).ok());
  EXPECT_FALSE(f.setPose(Eigen::Isometry3d::Identity(), poseCov(kNaN, 1), 2.0).ok());
  EXPECT_FALSE(f.stateAt(kNaN).ok());
  EXPECT_EQ(f.diagnostics().source(MeasurementSource::kTwist).rejected_invalid, 3u);
}

TEST(Ekf, TinyMeasurementCovarianceKeepsCovarianceSymmetricPositiveDefinite) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(1.0, 0.1), 0.0).ok());
  for (int k = 1; k <= 100; ++k) {
    const double t = 0.01 * k;
    f.processTwist(stillTwist(t));
    const FuseReport r = f.processPose(
        PoseMeasurement::full(t, Eigen::Isometry3d::Identity(), Matrix6d::Identity() * 1e-14));
    EXPECT_TRUE(r.fused()) << r.reason;
    ASSERT_TRUE(symmetricPositiveDefinite(f.state().P)) << "step " << k;
  }
  EXPECT_LT(f.diagnostics().max_position_sigma_m, 1e-3);
}

TEST(Ekf, YawInnovationIsWrappedAcrossPi) {
  Ekf f = makeFilter();
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.linear() = rotationFromRpy(0.0, 0.0, 3.13);
  ASSERT_TRUE(f.reset(start, poseCov(0.2, 0.05), 0.0).ok());
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.04, 0.04, 0.0025).asDiagonal();
  // -3.13 rad is 0.023 rad from 3.13 across the wrap, not 6.26 rad.
  const FuseReport r = f.processPose(PoseMeasurement::planar(0.01, 0.0, 0.0, -3.13, cov));
  ASSERT_TRUE(r.fused()) << r.reason;
  EXPECT_LT(r.mahalanobis_sq, 1.0);
  const double yaw = f.state().x(kStateYaw);
  EXPECT_GT(std::abs(yaw), 3.13);  // moved towards pi (either sign), not towards zero
  EXPECT_GE(yaw, -M_PI);
  EXPECT_LT(yaw, M_PI);
}

TEST(Ekf, TooOldBackwardsAndForwardStampsAreReported) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 100.0).ok());
  feedStill(&f, 100.01, 103.0);
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.04, 0.04, 1e-4).asDiagonal();
  const EkfState before = f.state();

  FuseReport r = f.processPose(PoseMeasurement::planar(100.5, 0, 0, 0, cov));  // 2.5 s late
  EXPECT_EQ(r.outcome, FuseOutcome::kRejectedTooOld);
  EXPECT_NE(r.reason.find("history_length_s"), std::string::npos) << r.reason;
  r = f.processPose(PoseMeasurement::planar(99.9, 0, 0, 0, cov));  // before the reset
  EXPECT_EQ(r.outcome, FuseOutcome::kRejectedTooOld);
  r = f.processPose(PoseMeasurement::planar(90.0, 0, 0, 0, cov));  // a looping bag
  EXPECT_EQ(r.outcome, FuseOutcome::kTimeWentBackwards);
  EXPECT_NE(r.reason.find("reset"), std::string::npos) << r.reason;
  r = f.processTwist(stillTwist(203.0));
  EXPECT_EQ(r.outcome, FuseOutcome::kTimeJumpedForward);
  EXPECT_TRUE(f.state().x == before.x);
  EXPECT_EQ(f.state().time_s, before.time_s);
  const EkfDiagnostics d = f.diagnostics();
  EXPECT_EQ(d.time_backwards_events, 1u);
  EXPECT_EQ(d.time_forward_jump_events, 1u);
  EXPECT_EQ(d.source(MeasurementSource::kPose).rejected_too_old, 2u);

  // The caller resets at the earlier time and the filter runs again.
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 90.0).ok());
  EXPECT_TRUE(f.processPose(PoseMeasurement::planar(90.1, 0, 0, 0, cov)).fused());
  EXPECT_DOUBLE_EQ(f.time(), 90.1);
}

TEST(Ekf, HistoryIsBoundedInTime) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 0.0).ok());
  feedStill(&f, 0.01, 10.0);
  const EkfDiagnostics d = f.diagnostics();
  EXPECT_LE(d.history_span_s, f.options().history_length_s + 0.011);
  EXPECT_GE(d.history_span_s, f.options().history_length_s - 0.011);
  EXPECT_LE(d.history_entries, 4u * 202u);  // 4 measurements per 10 ms over 2 s
  EkfOptions o;
  o.max_history_entries = 50;
  Ekf g = makeFilter(o);
  ASSERT_TRUE(g.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 0.0).ok());
  feedStill(&g, 0.01, 3.0);
  EXPECT_EQ(g.diagnostics().history_entries, 50u);
}

TEST(Ekf, StateAtPredictsWithoutMutating) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 0.0).ok());
  for (int k = 1; k <= 300; ++k) {
    TwistMeasurement t = stillTwist(0.01 * k);
    t.linear_mps.x() = 5.0;
    f.processTwist(t);
  }
  const EkfState now = f.state();
  ASSERT_NEAR(now.x(kStateVx), 5.0, 1e-2);
  const auto ahead = f.stateAt(3.5);
  ASSERT_TRUE(ahead.ok()) << ahead.error();
  EXPECT_NEAR(ahead->x(kStateX) - now.x(kStateX), 0.5 * now.x(kStateVx), 1e-2);
  EXPECT_GT(ahead->P(kStateX, kStateX), now.P(kStateX, kStateX));
  EXPECT_TRUE(f.state().x == now.x);
  EXPECT_EQ(f.time(), 3.0);
  const auto past = f.stateAt(2.505);  // within the history: from the stored state at 2.50
  ASSERT_TRUE(past.ok()) << past.error();
  EXPECT_NEAR(now.x(kStateX) - past->x(kStateX), 0.495 * 5.0, 0.05);
  EXPECT_FALSE(f.stateAt(0.5).ok());   // older than the history
  EXPECT_FALSE(f.stateAt(10.0).ok());  // beyond max_prediction_gap_s
}

TEST(Ekf, SetPoseKeepsVelocityAndClearsHistory) {
  Ekf f = makeFilter();
  ASSERT_TRUE(f.reset(Eigen::Isometry3d::Identity(), poseCov(0.2, 0.02), 0.0).ok());
  for (int k = 1; k <= 100; ++k) {
    TwistMeasurement t = stillTwist(0.01 * k);
    t.linear_mps.x() = 5.0;
    f.processTwist(t);
  }
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() << 100.0, 200.0, 0.0;
  p.linear() = rotationFromRpy(0.0, 0.0, 1.0);
  ASSERT_TRUE(f.setPose(p, poseCov(0.5, 0.05), 0.5).ok());  // earlier stamp: applies at 1.0
  EXPECT_DOUBLE_EQ(f.time(), 1.0);
  EXPECT_TRUE(f.pose().isApprox(p, 1e-12));
  EXPECT_NEAR(f.state().x(kStateVx), 5.0, 1e-2);
  EXPECT_NEAR(f.state().P(kStateX, kStateX), 0.25, 1e-12);
  EXPECT_EQ(f.state().P(kStateX, kStateVx), 0.0);
  EXPECT_EQ(f.diagnostics().history_entries, 0u);
  EXPECT_EQ(f.processTwist(stillTwist(0.9)).outcome, FuseOutcome::kRejectedTooOld);
}

TEST(Ekf, LatePoseGivesTheSameStateAsInOrderDelivery) {
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.04, 0.04, 1e-4).asDiagonal();
  const PoseMeasurement pose = PoseMeasurement::planar(1.005, 0.3, -0.2, 0.01, cov);
  Ekf in_order = makeFilter(), late = makeFilter();
  for (Ekf* f : {&in_order, &late}) {
    ASSERT_TRUE(f->reset(Eigen::Isometry3d::Identity(), poseCov(0.5, 0.05), 0.0).ok());
    feedStill(f, 0.01, 1.0);
  }
  EXPECT_TRUE(in_order.processPose(pose).fused());
  feedStill(&in_order, 1.01, 1.15);
  feedStill(&late, 1.01, 1.15);
  const FuseReport r = late.processPose(pose);
  EXPECT_TRUE(r.fused()) << r.reason;
  EXPECT_EQ(r.replayed, 15 * 4);
  EXPECT_EQ(late.diagnostics().delayed_measurements, 1u);
  EXPECT_DOUBLE_EQ(late.time(), in_order.time());
  EXPECT_LT((late.state().x - in_order.state().x).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((late.state().P - in_order.state().P).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(std::abs(late.state().x(kStateX)), 0.05);  // the pose did move the state
}

}  // namespace
}  // namespace gmm_localization
