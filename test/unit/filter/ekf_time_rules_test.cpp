// The EKF's time rules per message: one IMU message stamped far in the future is one forward
// jump (not one per part), and a single stale IMU or odometry message (~6 s old) is dropped with
// a reason and counted; only a sustained run of stale or far-future messages stops the filter
// (LocalizationFilter, which the ekf nodelet and LocalizerPipeline share).
#include <cmath>

#include <gtest/gtest.h>

#include "gmm_localization/core/filter/ekf.h"
#include "gmm_localization/core/localization/localization_filter.h"

namespace gmm_localization {
namespace {

constexpr double kT0 = 100.0;

Matrix6d poseCov(double sigma_xy, double sigma_angle) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_xy * sigma_xy,
      sigma_angle * sigma_angle, sigma_angle * sigma_angle, sigma_angle * sigma_angle;
  return c;
}

TwistMeasurement stillTwist(double t) {
  TwistMeasurement m;
  m.stamp_s = t;
  m.covariance = Matrix6d::Identity() * 1e-4;
  return m;
}

/// A level, resting IMU with all three parts present.
ImuMeasurement levelImu(double t) {
  ImuMeasurement m;
  m.stamp_s = t;
  m.has_orientation = m.has_angular_velocity = m.has_linear_acceleration = true;
  m.orientation_covariance = Eigen::Matrix3d::Identity() * 1e-4;
  m.angular_velocity_covariance = Eigen::Matrix3d::Identity() * 1e-5;
  m.linear_acceleration_mps2 = Eigen::Vector3d(0, 0, EkfOptions().gravity_mps2);
  m.linear_acceleration_covariance = Eigen::Matrix3d::Identity() * 1e-3;
  return m;
}

/// A running filter, fed at 100 Hz from kT0 to t1 (inclusive).
LocalizationFilter runningFilter(double t1) {
  auto created = LocalizationFilter::create(EkfOptions(), FilterPolicyOptions());
  EXPECT_TRUE(created.ok()) << created.error();
  LocalizationFilter f = std::move(created).value();
  EXPECT_TRUE(f.addMatch(kT0, Pose6(), poseCov(0.05, 0.01)).fused());
  for (int k = 1; kT0 + 0.01 * k <= t1 + 1e-9; ++k) {
    f.addImu(levelImu(kT0 + 0.01 * k));
    f.addTwist(stillTwist(kT0 + 0.01 * k));
  }
  EXPECT_TRUE(f.active());
  return f;
}

TEST(EkfTimeRules, OneFarFutureImuMessageIsOneReportAndOneJump) {
  auto f = Ekf::create(EkfOptions());
  ASSERT_TRUE(f.ok());
  ASSERT_TRUE(f->reset(Eigen::Isometry3d::Identity(), poseCov(0.1, 0.01), kT0).ok());
  ASSERT_TRUE(f->processTwist(stillTwist(kT0 + 0.5)).fused());
  const EkfState before = f->state();
  const std::vector<FuseReport> reports = f->processImu(levelImu(kT0 + 3600.0));
  ASSERT_EQ(reports.size(), 1u) << "one report for the message, not one per part";
  EXPECT_EQ(reports[0].outcome, FuseOutcome::kTimeJumpedForward);
  EXPECT_NE(reports[0].reason.find("max_prediction_gap_s"), std::string::npos) << reports[0].reason;
  EXPECT_EQ(f->diagnostics().time_forward_jump_events, 1u);
  EXPECT_TRUE(f->state().x == before.x);
  EXPECT_EQ(f->time(), before.time_s);
  // The next in-time message of every part is fused as before.
  for (const FuseReport& r : f->processImu(levelImu(kT0 + 0.51))) {
    EXPECT_TRUE(r.fused()) << sourceName(r.source) << ": " << r.reason;
  }
}

TEST(EkfTimeRules, OneFarFutureImuMessageNeverStopsTheFilter) {
  LocalizationFilter f = runningFilter(kT0 + 1.0);
  const std::vector<FuseReport> reports = f.addImu(levelImu(kT0 + 1e5));
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].outcome, FuseOutcome::kTimeJumpedForward);
  EXPECT_FALSE(reports[0].reason.empty());
  EXPECT_TRUE(f.active());
  EXPECT_EQ(f.stops(), 0u);
  // In-time messages keep it running and end the run of far-future stamps.
  EXPECT_TRUE(f.addTwist(stillTwist(kT0 + 1.01)).fused());
  for (int k = 0; k < 2; ++k) f.addImu(levelImu(kT0 + 1e5 + k));
  EXPECT_TRUE(f.active()) << "two far-future messages are fewer than forward_jump_reset_count";
  EXPECT_TRUE(f.addTwist(stillTwist(kT0 + 1.02)).fused());
  // A sustained run (forward_jump_reset_count messages in a row, counted per message) stops it.
  const int run = FilterPolicyOptions().forward_jump_reset_count;
  for (int k = 0; k < run - 1; ++k) {
    f.addImu(levelImu(kT0 + 1e5 + k));
    EXPECT_TRUE(f.active()) << "after " << k + 1 << " far-future IMU messages";
  }
  f.addImu(levelImu(kT0 + 1e5 + run));
  EXPECT_FALSE(f.active());
  EXPECT_EQ(f.stops(), 1u);
}

TEST(EkfTimeRules, SingleStaleImuOrOdometryMessageIsDroppedNotAReset) {
  LocalizationFilter f = runningFilter(kT0 + 8.0);
  const double filter_time = f.ekf().time();
  const EkfState before = f.ekf().state();

  // One odometry message stamped 6 s old (beyond time_backwards_tolerance_s = 5 s).
  const FuseReport twist = f.addTwist(stillTwist(filter_time - 6.0));
  EXPECT_FALSE(twist.fused());
  EXPECT_NE(twist.outcome, FuseOutcome::kTimeWentBackwards);
  EXPECT_FALSE(twist.reason.empty());
  EXPECT_TRUE(f.active());
  // The next in-time message ends the run; then one stale IMU message.
  EXPECT_TRUE(f.addTwist(stillTwist(filter_time + 0.01)).fused());
  const std::vector<FuseReport> imu = f.addImu(levelImu(filter_time - 6.0));
  ASSERT_EQ(imu.size(), 1u) << "one report for the message";
  EXPECT_FALSE(imu[0].fused());
  EXPECT_NE(imu[0].outcome, FuseOutcome::kTimeWentBackwards);
  EXPECT_FALSE(imu[0].reason.empty());
  EXPECT_TRUE(f.active());
  EXPECT_EQ(f.stops(), 0u);
  EXPECT_GT(f.ekf().time(), before.time_s) << "the filter kept its time line";
  EXPECT_EQ(f.ekf().diagnostics().resets, 1u) << "only the start";
  EXPECT_EQ(f.ekf().diagnostics().time_backwards_events, 0u);
}

TEST(EkfTimeRules, SustainedRunOfStaleMessagesStops) {
  LocalizationFilter f = runningFilter(kT0 + 8.0);
  const double filter_time = f.ekf().time();
  // A clock that went back by 6 s for good: every message is stale; the filter stops after a
  // short run and a new initial pose (or match) restarts it there.
  double t = filter_time - 6.0;
  int messages = 0;
  while (f.active() && messages < 1000) {
    f.addImu(levelImu(t));
    f.addTwist(stillTwist(t + 0.005));
    messages += 2;
    t += 0.01;
  }
  EXPECT_FALSE(f.active());
  EXPECT_EQ(f.stops(), 1u);
  EXPECT_GT(messages, 2) << "more than one message";
  EXPECT_LE(messages, 100) << "a run of a fraction of a second";
  EXPECT_EQ(f.ekf().diagnostics().time_backwards_events, 1u);
}

TEST(EkfTimeRules, EkfCountsStaleMessagesAndReportsARunAsTimeGoingBackwards) {
  EkfOptions o;
  o.stale_reset_count = 4;
  auto f = Ekf::create(o);
  ASSERT_TRUE(f.ok());
  ASSERT_TRUE(f->reset(Eigen::Isometry3d::Identity(), poseCov(0.1, 0.01), kT0).ok());
  for (double t = kT0 + 1.0; t <= kT0 + 8.0; t += 1.0) {
    ASSERT_TRUE(f->processTwist(stillTwist(t)).fused());
  }
  const EkfState before = f->state();
  // Stale runs shorter than stale_reset_count, each ended by an in-time message.
  for (int round = 0; round < 3; ++round) {
    for (int k = 0; k < o.stale_reset_count - 1; ++k) {
      const FuseReport r = f->processTwist(stillTwist(kT0 + 2.0 + 0.01 * k));
      EXPECT_EQ(r.outcome, FuseOutcome::kRejectedStale) << r.reason;
      EXPECT_NE(r.reason.find("time_backwards_tolerance_s"), std::string::npos) << r.reason;
      EXPECT_NE(r.reason.find("stale"), std::string::npos) << r.reason;
      EXPECT_EQ(f->diagnostics().consecutive_stale, k + 1);
    }
    EXPECT_TRUE(f->state().x == before.x) << "a stale message never touches the state";
    EXPECT_TRUE(f->processTwist(stillTwist(kT0 + 8.0 + 0.01 * (round + 1))).fused());
    EXPECT_EQ(f->diagnostics().consecutive_stale, 0);
  }
  EkfDiagnostics d = f->diagnostics();
  EXPECT_EQ(d.source(MeasurementSource::kTwist).rejected_stale,
            3u * static_cast<uint64_t>(o.stale_reset_count - 1));
  EXPECT_EQ(d.time_backwards_events, 0u);
  // A stale IMU message counts once in the run.
  const std::vector<FuseReport> imu = f->processImu(levelImu(kT0 + 2.0));
  ASSERT_EQ(imu.size(), 1u);
  EXPECT_EQ(imu[0].outcome, FuseOutcome::kRejectedStale);
  EXPECT_EQ(f->diagnostics().consecutive_stale, 1);
  EXPECT_EQ(f->diagnostics().source(MeasurementSource::kImuOrientation).rejected_stale, 1u);
  // The run reaching stale_reset_count reports time going backwards.
  for (int k = 1; k < o.stale_reset_count - 1; ++k) {
    EXPECT_EQ(f->processTwist(stillTwist(kT0 + 2.0)).outcome, FuseOutcome::kRejectedStale);
  }
  const FuseReport last = f->processPose(
      PoseMeasurement::planar(kT0 + 2.0, 0, 0, 0, Eigen::Vector3d(0.04, 0.04, 1e-4).asDiagonal()));
  EXPECT_EQ(last.outcome, FuseOutcome::kTimeWentBackwards) << last.reason;
  EXPECT_NE(last.reason.find("stale_reset_count"), std::string::npos) << last.reason;
  EXPECT_EQ(f->diagnostics().time_backwards_events, 1u);
  // One stamp beyond time_backwards_reset_s is time going backwards at once.
  ASSERT_TRUE(f->reset(Eigen::Isometry3d::Identity(), poseCov(0.1, 0.01), kT0 + 20.0).ok());
  EXPECT_EQ(f->diagnostics().consecutive_stale, 0) << "reset starts a new time line";
  const FuseReport loop = f->processTwist(stillTwist(kT0 + 20.0 - o.time_backwards_reset_s - 1));
  EXPECT_EQ(loop.outcome, FuseOutcome::kTimeWentBackwards);
  EXPECT_NE(loop.reason.find("time_backwards_reset_s"), std::string::npos) << loop.reason;
}

TEST(EkfTimeRules, OptionsAreValidated) {
  EkfOptions o;
  o.stale_reset_count = 0;
  EXPECT_NE(o.validate().error().find("stale_reset_count"), std::string::npos);
  o = EkfOptions();
  o.time_backwards_reset_s = o.time_backwards_tolerance_s - 1.0;  // below the tolerance
  EXPECT_NE(o.validate().error().find("time_backwards_reset_s"), std::string::npos);
  o.time_backwards_reset_s = NAN;
  EXPECT_FALSE(o.validate().ok());
  EXPECT_EQ(std::string(outcomeName(FuseOutcome::kRejectedStale)), "rejected_stale");
}

}  // namespace
}  // namespace gmm_localization
