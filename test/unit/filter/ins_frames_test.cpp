// The INS adapter's maths (core/filter/ins_frames.h) on synthetic ground truth: a vehicle
// driving a circle with its INS at an offset lever arm, reporting in each convention (world ENU
// and NED velocities, FLU and FRD bodies, the Autoware driver's setEuler quaternion); the
// base_link twist equals the truth, and dead reckoning over a full circle ends at the truth.
#include "gmm_localization/core/filter/ins_frames.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "support/ins_circle.h"

namespace gmm_localization {
namespace {

using test::InsCircle;

Eigen::Isometry3d mount() {
  // The INS 1.2 m ahead, 0.4 m right and 1.6 m above base_link, mounted 2 deg off in yaw and
  // 0.6 deg in roll (the adapter must use the rotation of the TF too, not only its offset).
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(1.2, -0.4, 1.6);
  return T;
}

InsCircle circle() {
  InsCircle c;
  c.base_T_child = mount();
  return c;
}

/// Applanix angles of an NED <- FRD rotation (Z-Y-X).
ApplanixAngles anglesOf(const Eigen::Matrix3d& ned_R_frd) {
  ApplanixAngles a;
  a.heading = std::atan2(ned_R_frd(1, 0), ned_R_frd(0, 0));
  a.pitch = -std::asin(ned_R_frd(2, 0));
  a.roll = std::atan2(ned_R_frd(2, 1), ned_R_frd(2, 2));
  return a;
}

/// What a driver of the given convention reports at time t.
InsReport report(const InsCircle& c, double t, const InsConvention& conv) {
  const Eigen::Isometry3d child = c.childPose(t);
  const Eigen::Matrix3d M = enuFromNed(), F = fluFromFrd();
  const bool frd = conv.body_axes == InsBodyAxes::kFrd;
  InsReport r;
  r.stamp_s = 1000.0 + t;
  const Eigen::Vector3d v_enu = c.childWorldVelocity(t);
  switch (conv.velocity_frame) {
    case InsVelocityFrame::kBody:
      r.linear_velocity =
          (frd ? F : Eigen::Matrix3d::Identity()) * child.linear().transpose() * v_enu;
      break;
    case InsVelocityFrame::kEnu:
      r.linear_velocity = v_enu;
      break;
    case InsVelocityFrame::kNed:
      r.linear_velocity = M * v_enu;
      break;
  }
  r.angular_velocity = (frd ? F : Eigen::Matrix3d::Identity()) * c.childRates(t);
  const Eigen::Matrix3d body_R = frd ? Eigen::Matrix3d(child.linear() * F) : child.linear();
  switch (conv.attitude) {
    case InsAttitude::kEnu:
      r.orientation = Eigen::Quaterniond(body_R);
      r.position = child.translation();
      break;
    case InsAttitude::kNed:
      r.orientation = Eigen::Quaterniond(M * body_R);
      r.position = M * child.translation();
      break;
    case InsAttitude::kNedSetEuler: {
      const ApplanixAngles a = anglesOf(M * child.linear() * F);
      r.orientation = setEulerQuaternion(a.heading, a.pitch, a.roll);
      r.position = M * child.translation();
      break;
    }
  }
  return r;
}

InsConvention convention(InsVelocityFrame v, InsBodyAxes b, InsAttitude a) {
  InsConvention c;
  c.velocity_frame = v;
  c.body_axes = b;
  c.attitude = a;
  return c;
}

/// The conventions the adapter supports, the two drivers' among them.
std::vector<InsConvention> conventions() {
  return {
      convention(InsVelocityFrame::kBody, InsBodyAxes::kFlu, InsAttitude::kEnu),  // REP-105
      convention(InsVelocityFrame::kEnu, InsBodyAxes::kFlu, InsAttitude::kEnu),   // Clearpath
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFrd, InsAttitude::kNedSetEuler),  // Autoware
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFrd, InsAttitude::kNed),  // aerospace
      convention(InsVelocityFrame::kBody, InsBodyAxes::kFrd, InsAttitude::kNed),
      convention(InsVelocityFrame::kEnu, InsBodyAxes::kFrd, InsAttitude::kEnu),
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFlu, InsAttitude::kEnu),
  };
}

std::string describe(const InsConvention& c) {
  return std::string("velocity ") + insVelocityFrameName(c.velocity_frame) + ", body " +
         insBodyAxesName(c.body_axes) + ", attitude " + insAttitudeName(c.attitude);
}

TEST(InsFrames, AxisConversionsAreTheUsualPermutations) {
  EXPECT_TRUE((enuFromNed() * Eigen::Vector3d(1, 2, 3)).isApprox(Eigen::Vector3d(2, 1, -3)));
  EXPECT_TRUE((fluFromFrd() * Eigen::Vector3d(1, 2, 3)).isApprox(Eigen::Vector3d(1, -2, -3)));
  EXPECT_TRUE((enuFromNed() * enuFromNed()).isIdentity());
  EXPECT_TRUE((fluFromFrd() * fluFromFrd()).isIdentity());
  // A vehicle heading north-east, level: ENU yaw 45 deg.
  InsConvention ned = convention(InsVelocityFrame::kNed, InsBodyAxes::kFrd, InsAttitude::kNed);
  const Eigen::Quaterniond q = childAttitudeEnuFlu(nedFrdFromApplanix({0.0, 0.0, M_PI / 4}), ned);
  const Eigen::Vector3d forward = q * Eigen::Vector3d::UnitX();
  EXPECT_TRUE(forward.isApprox(Eigen::Vector3d(1, 1, 0).normalized(), 1e-12));
  EXPECT_TRUE((q * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
}

TEST(InsFrames, ApplanixAnglesInEnuAreClearpathsRollMinusPitchNinetyMinusHeading) {
  // applanix_bridge publishes RPY(roll, -pitch, 90 deg - heading) as the ENU <- FLU attitude:
  // the same rotation as ENU <- NED * Rz(h) Ry(p) Rx(r) * FRD <- FLU.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), tilt(-1.2, 1.2);
  for (int i = 0; i < 100; ++i) {
    const ApplanixAngles a{tilt(rng), tilt(rng), angle(rng)};
    const Eigen::Matrix3d ours =
        enuFromNed() * nedFrdFromApplanix(a).toRotationMatrix() * fluFromFrd();
    const Eigen::Matrix3d clearpath =
        (Eigen::AngleAxisd(M_PI / 2 - a.heading, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(-a.pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(a.roll, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    EXPECT_TRUE(ours.isApprox(clearpath, 1e-12)) << i;
  }
}

TEST(InsFrames, SetEulerQuaternionIsTf2sAndItsAnglesComeBack) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-M_PI + 1e-3, M_PI - 1e-3), pitch(-1.5, 1.5);
  for (int i = 0; i < 200; ++i) {
    const double h = angle(rng), p = pitch(rng), r = angle(rng);
    // tf2::Quaternion::setEuler(yaw, pitch, roll), component by component (tf2/LinearMath).
    const double cy = std::cos(h / 2), sy = std::sin(h / 2), cp = std::cos(p / 2),
                 sp = std::sin(p / 2), cr = std::cos(r / 2), sr = std::sin(r / 2);
    const Eigen::Quaterniond tf2(cr * cp * cy + sr * sp * sy, cr * sp * cy + sr * cp * sy,
                                 cr * cp * sy - sr * sp * cy, sr * cp * cy - cr * sp * sy);
    const Eigen::Quaterniond q = setEulerQuaternion(h, p, r);
    EXPECT_NEAR(std::abs(q.dot(tf2)), 1.0, 1e-12) << i;
    const ApplanixAngles a = applanixFromSetEuler(q);
    EXPECT_NEAR(a.heading, h, 1e-9);
    EXPECT_NEAR(a.pitch, p, 1e-9);
    EXPECT_NEAR(a.roll, r, 1e-9);
  }
  // A heading of 270 deg (the Applanix range is 0-360) comes back as -90 deg: the same attitude.
  const ApplanixAngles a = applanixFromSetEuler(setEulerQuaternion(1.5 * M_PI, 0.1, 0.2));
  EXPECT_NEAR(a.heading, -0.5 * M_PI, 1e-12);
}

TEST(InsFrames, TwistTransformIsTheRigidBodyVelocityOfAnotherPoint) {
  // Finite differences of two frames fixed on one moving body.
  const InsCircle c = circle();
  const double t = 3.7, dt = 1e-6;
  const Eigen::Isometry3d base_T_child = mount();
  Eigen::Matrix<double, 6, 1> child_twist;
  child_twist << c.childPose(t).linear().transpose() * c.childWorldVelocity(t), c.childRates(t);
  const Eigen::Matrix<double, 6, 1> base = twistTransform(base_T_child) * child_twist;
  const Eigen::Isometry3d a = c.pose(t - dt), b = c.pose(t + dt);
  const Eigen::Vector3d v_fd =
      a.linear().transpose() * (b.translation() - a.translation()) / (2 * dt);
  EXPECT_TRUE(base.head<3>().isApprox(v_fd, 1e-6))
      << base.transpose() << " fd " << v_fd.transpose();
  EXPECT_TRUE(base.isApprox(c.bodyTwist(t), 1e-9)) << base.transpose();
}

TEST(InsFrames, EveryConventionGivesTheTrueBaseLinkTwist) {
  const InsCircle c = circle();
  for (const InsConvention& conv : conventions()) {
    ASSERT_EQ(conv.validate(), "");
    for (double t = 0.0; t < 31.5; t += 0.37) {
      const auto s = insSampleInBaseLink(report(c, t, conv), conv, mount());
      ASSERT_TRUE(s.ok()) << s.error();
      EXPECT_TRUE(s->twist.isApprox(c.bodyTwist(t), 1e-9))
          << describe(conv) << " t " << t << ": " << s->twist.transpose() << " vs "
          << c.bodyTwist(t).transpose();
      EXPECT_TRUE(s->world_T_base.isApprox(c.pose(t), 1e-9)) << describe(conv) << " t " << t;
    }
  }
}

TEST(InsFrames, ReadingEastNorthAsForwardLeftIsWrongWhereTheAdapterIsRight) {
  // What the EKF did before: the world velocity taken as the body twist. Heading north-west the
  // vehicle seemed to drive sideways and backwards.
  InsCircle c = circle();
  c.yaw0 = 2.0;
  const InsConvention enu =
      convention(InsVelocityFrame::kEnu, InsBodyAxes::kFlu, InsAttitude::kEnu);
  const InsReport r = report(c, 0.0, enu);
  EXPECT_GT((r.linear_velocity - c.bodyTwist(0.0).head<3>()).norm(), 5.0);
  const auto s = insSampleInBaseLink(r, enu, mount());
  ASSERT_TRUE(s.ok());
  EXPECT_NEAR(s->twist(0), c.speed0, 1e-9);
  EXPECT_NEAR(s->twist(1), 0.0, 1e-9);
}

/// Dead reckoning from t = 0 to `duration` at about `rate_hz` (the last sample at `duration`).
Eigen::Isometry3d deadReckon(const InsCircle& c, const InsConvention& conv, double duration,
                             double rate_hz, InsPoseSource source = InsPoseSource::kDeadReckoning) {
  InsOdometryOptions o;
  o.pose_source = source;
  InsOdometry odom(o);
  const int n = static_cast<int>(std::lround(duration * rate_hz));
  InsOdometry::Update u;
  for (int i = 0; i <= n; ++i) {
    const auto s = insSampleInBaseLink(report(c, i * duration / n, conv), conv, mount());
    EXPECT_TRUE(s.ok());
    u = odom.add(*s);
    EXPECT_EQ(u.step, i == 0 ? InsOdometryStep::kStarted : InsOdometryStep::kIntegrated);
  }
  return u.odom_T_base;
}

/// The truth in the adapter's odom frame: ENU axes, origin at base_link's first position.
Eigen::Isometry3d truthInOdom(const InsCircle& c, double t) {
  Eigen::Isometry3d T = c.pose(t);
  T.translation() -= c.position(0.0);
  return T;
}

TEST(InsFrames, DeadReckoningAroundTheCircleEndsAtTheTruth) {
  const InsCircle c = circle();
  const double full_circle = 2 * M_PI / c.yaw_rate;  // 31.4 s, 314 m, radius 50 m
  for (const InsConvention& conv : conventions()) {
    const Eigen::Isometry3d end = deadReckon(c, conv, full_circle, 100.0);
    const Eigen::Isometry3d truth = truthInOdom(c, full_circle);
    // Constant body twist: the SE(3) exponential is exact up to rounding.
    EXPECT_LT((end.translation() - truth.translation()).norm(), 1e-6) << describe(conv);
    EXPECT_LT(Eigen::AngleAxisd(end.linear().transpose() * truth.linear()).angle(), 1e-9)
        << describe(conv);
    // The circle closes: back where it started (the pitch climbs it by 314 m * sin(pitch)).
    EXPECT_LT((end.translation().head<2>()).norm(), 1e-6);
  }
}

TEST(InsFrames, DeadReckoningWithAVaryingSpeedEndsWithinAMillimetre) {
  InsCircle c = circle();
  c.speed_amplitude = 4.0;  // 6-14 m/s, accelerating at up to 6.3 m/s^2
  const double full_circle = 2 * M_PI / c.yaw_rate;
  const InsConvention autoware =
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFrd, InsAttitude::kNedSetEuler);
  const Eigen::Isometry3d end = deadReckon(c, autoware, full_circle, 50.0);
  const Eigen::Isometry3d truth = truthInOdom(c, full_circle);
  EXPECT_LT((end.translation() - truth.translation()).norm(), 1e-3)
      << end.translation().transpose() << " vs " << truth.translation().transpose();
  EXPECT_LT(Eigen::AngleAxisd(end.linear().transpose() * truth.linear()).angle(), 1e-9);
}

TEST(InsFrames, DriverPoseSourceIsTheDriversPoseAtBaseLinkFromTheFirstPosition) {
  const InsCircle c = circle();
  const InsConvention clearpath =
      convention(InsVelocityFrame::kEnu, InsBodyAxes::kFlu, InsAttitude::kEnu);
  const Eigen::Isometry3d end = deadReckon(c, clearpath, 10.0, 20.0, InsPoseSource::kDriver);
  EXPECT_TRUE(end.isApprox(truthInOdom(c, 10.0), 1e-9));
}

TEST(InsFrames, TwistCovarianceIsRotatedAndUnknownBlocksGetDefaults) {
  InsCircle c = circle();
  c.base_T_child = Eigen::Isometry3d::Identity();
  c.roll = c.pitch = 0.0;
  c.yaw0 = 0.5 * M_PI;  // heading north: east is -y (right) in the body
  const InsConvention autoware =
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFrd, InsAttitude::kNedSetEuler);
  InsReport r = report(c, 0.0, autoware);
  // Autoware's driver with RMS: variances of north, east, down velocity only.
  r.twist_covariance.diagonal() << 0.01, 0.04, 0.09, 0.0, 0.0, 0.0;
  InsCovarianceDefaults d;
  d.angular_sigma_radps = 0.02;
  auto s = insSampleInBaseLink(r, autoware, Eigen::Isometry3d::Identity(), d);
  ASSERT_TRUE(s.ok());
  Eigen::Matrix<double, 6, 1> expected;
  expected << 0.01, 0.04, 0.09, 4e-4, 4e-4, 4e-4;  // north = forward, east = right, down
  EXPECT_TRUE(s->twist_covariance.diagonal().isApprox(expected, 1e-9))
      << s->twist_covariance.diagonal().transpose();
  // Without RMS the driver sets covariance[0] = -1: unknown, all zeros out (EKF defaults).
  r.twist_covariance.setZero();
  r.twist_covariance(0, 0) = -1.0;
  s = insSampleInBaseLink(r, autoware, mount(), d);
  ASSERT_TRUE(s.ok());
  EXPECT_TRUE(s->twist_covariance.isZero());
  EXPECT_TRUE(s->pose_covariance.isZero());
  // With a lever arm the angular uncertainty adds to the linear one (v = R v_c + p x w).
  r.twist_covariance.diagonal() << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
  s = insSampleInBaseLink(r, autoware, mount(), d);
  ASSERT_TRUE(s.ok());
  EXPECT_GT(s->twist_covariance(0, 0), 0.01);
  EXPECT_TRUE(s->twist_covariance.isApprox(s->twist_covariance.transpose()));
  EXPECT_GT(s->twist_covariance.ldlt().vectorD().minCoeff(), 0.0);
}

TEST(InsFrames, PoseCovarianceOfANedDriverComesOutInEnu) {
  const InsCircle c = circle();
  const InsConvention ned =
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFrd, InsAttitude::kNed);
  InsReport r = report(c, 1.0, ned);
  r.pose_covariance.diagonal() << 1.0, 4.0, 9.0, 0.1, 0.2, 0.3;  // north, east, down, ...
  const auto s = insSampleInBaseLink(r, ned, mount());
  ASSERT_TRUE(s.ok());
  Eigen::Matrix<double, 6, 1> expected;
  expected << 4.0, 1.0, 9.0, 0.1, 0.2, 0.3;
  EXPECT_TRUE(s->pose_covariance.diagonal().isApprox(expected));
}

TEST(InsFrames, BadReportsAreRejectedWithAReason) {
  const InsCircle c = circle();
  const InsConvention enu =
      convention(InsVelocityFrame::kEnu, InsBodyAxes::kFlu, InsAttitude::kEnu);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  InsReport r = report(c, 0.0, enu);
  r.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  auto s = insSampleInBaseLink(r, enu, mount());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("unit quaternion"), std::string::npos) << s.error();
  r = report(c, 0.0, enu);
  r.linear_velocity.x() = nan;
  EXPECT_FALSE(insSampleInBaseLink(r, enu, mount()).ok());
  r = report(c, 0.0, enu);
  r.stamp_s = nan;
  EXPECT_FALSE(insSampleInBaseLink(r, enu, mount()).ok());
  r = report(c, 0.0, enu);
  r.twist_covariance(2, 2) = nan;
  EXPECT_FALSE(insSampleInBaseLink(r, enu, mount()).ok());
  Eigen::Isometry3d bad = mount();
  bad.translation().y() = nan;
  EXPECT_FALSE(insSampleInBaseLink(report(c, 0.0, enu), enu, bad).ok());
  InsConvention inconsistent =
      convention(InsVelocityFrame::kNed, InsBodyAxes::kFlu, InsAttitude::kNedSetEuler);
  EXPECT_NE(inconsistent.validate(), "");
}

TEST(InsFrames, OdometryDropsOutOfOrderStampsRestartsOnALoopAndReportsGaps) {
  const InsCircle c = circle();
  const InsConvention enu =
      convention(InsVelocityFrame::kEnu, InsBodyAxes::kFlu, InsAttitude::kEnu);
  auto sample = [&](double t) { return *insSampleInBaseLink(report(c, t, enu), enu, mount()); };
  InsOdometry odom;
  EXPECT_EQ(odom.add(sample(0.0)).step, InsOdometryStep::kStarted);
  EXPECT_EQ(odom.add(sample(0.1)).step, InsOdometryStep::kIntegrated);
  const Eigen::Isometry3d at = odom.pose();
  EXPECT_EQ(odom.add(sample(0.1)).step, InsOdometryStep::kDroppedOutOfOrder);  // repeated
  EXPECT_EQ(odom.add(sample(0.05)).step, InsOdometryStep::kDroppedOutOfOrder);
  EXPECT_TRUE(odom.pose().isApprox(at));
  // A 2 s dropout: integrated with the mean twist (a straight-ish chord), flagged.
  const InsOdometry::Update gap = odom.add(sample(2.1));
  EXPECT_EQ(gap.step, InsOdometryStep::kIntegratedOverGap);
  EXPECT_NEAR(gap.dt_s, 2.0, 1e-12);
  EXPECT_LT((gap.odom_T_base.translation() - truthInOdom(c, 2.1).translation()).norm(), 1e-6)
      << gap.odom_T_base.translation().transpose() << " vs "
      << truthInOdom(c, 2.1).translation().transpose();
  // The bag loops: started again at the origin with the attitude of that sample.
  const InsOdometry::Update back = odom.add(sample(0.0));
  EXPECT_EQ(back.step, InsOdometryStep::kRestarted);
  EXPECT_TRUE(back.odom_T_base.translation().isZero());
  EXPECT_TRUE(back.odom_T_base.linear().isApprox(c.rotation(0.0), 1e-9));
}

TEST(InsFrames, IntegrateBodyTwistHandlesZeroAndTinyRotations) {
  Eigen::Matrix<double, 6, 1> x;
  x << 2.0, 0.5, 0.0, 0.0, 0.0, 0.0;
  Eigen::Isometry3d T = integrateBodyTwist(Eigen::Isometry3d::Identity(), x, 0.5);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1.0, 0.25, 0.0)));
  x(5) = 1e-9;  // below the Taylor threshold: continuous with the closed form
  const Eigen::Isometry3d a = integrateBodyTwist(Eigen::Isometry3d::Identity(), x, 0.5);
  x(5) = 3e-6;
  const Eigen::Isometry3d b = integrateBodyTwist(Eigen::Isometry3d::Identity(), x, 0.5);
  EXPECT_LT((a.translation() - b.translation()).norm(), 1e-5);
  // A quarter turn at 1 m/s and 1 rad/s: the arc of radius 1.
  x << 1.0, 0.0, 0.0, 0.0, 0.0, 1.0;
  T = integrateBodyTwist(Eigen::Isometry3d::Identity(), x, M_PI / 2);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1.0, 1.0, 0.0), 1e-12));
}

TEST(InsFrames, NamesParseBack) {
  for (InsVelocityFrame f :
       {InsVelocityFrame::kBody, InsVelocityFrame::kEnu, InsVelocityFrame::kNed}) {
    InsVelocityFrame g = InsVelocityFrame::kBody;
    EXPECT_TRUE(parseInsVelocityFrame(insVelocityFrameName(f), g));
    EXPECT_EQ(f, g);
  }
  for (InsAttitude a : {InsAttitude::kEnu, InsAttitude::kNed, InsAttitude::kNedSetEuler}) {
    InsAttitude b = InsAttitude::kEnu;
    EXPECT_TRUE(parseInsAttitude(insAttitudeName(a), b));
    EXPECT_EQ(a, b);
  }
  InsBodyAxes axes = InsBodyAxes::kFlu;
  EXPECT_TRUE(parseInsBodyAxes("frd", axes));
  EXPECT_EQ(axes, InsBodyAxes::kFrd);
  InsPoseSource source = InsPoseSource::kDeadReckoning;
  EXPECT_TRUE(parseInsPoseSource("driver", source));
  EXPECT_EQ(source, InsPoseSource::kDriver);
  EXPECT_FALSE(parseInsPoseSource("Driver", source));
  InsVelocityFrame unchanged = InsVelocityFrame::kEnu;
  EXPECT_FALSE(parseInsVelocityFrame("NED", unchanged));
  EXPECT_EQ(unchanged, InsVelocityFrame::kEnu);
}

}  // namespace
}  // namespace gmm_localization
