// The localization policy shared by the matcher nodelet and LocalizerPipeline: window sizing
// from the prior's sigma, acceptance rules, the published covariance, the odometry buffer,
// prior selection with the relocalization state machine, and the filter supervision (start from
// a match, gate lockout, relocalize, time going backwards, default covariances).

#include "gmm_localization/core/localization/match_policy.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/localization/localization_filter.h"
#include "gmm_localization/core/localization/prior_tracker.h"

namespace gmm_localization {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Prior priorWithSigma(double sxy, double syaw) {
  Prior p;
  p.source = PriorSource::kEkf;
  p.covariance_xyh = Eigen::Vector3d(sxy * sxy, sxy * sxy, syaw * syaw).asDiagonal();
  return p;
}

TEST(LocalizationPolicyOptions, DefaultsValidAndErrorsNameTheKey) {
  LocalizationPolicyOptions o;
  EXPECT_EQ(o.validate(), "");
  o.window.min_half_xy_m = 20.0;  // above max
  EXPECT_NE(o.validate().find("min_half_xy_m"), std::string::npos) << o.validate();
  o = LocalizationPolicyOptions();
  o.acceptance.min_map_coverage = 1.5;
  EXPECT_NE(o.validate().find("acceptance.min_map_coverage = 1.5"), std::string::npos)
      << o.validate();
  o = LocalizationPolicyOptions();
  o.relocalization.max_consecutive_rejections = 0;
  EXPECT_NE(o.validate().find("max_consecutive_rejections"), std::string::npos);
}

TEST(SearchWindowFor, ThreeSigmaClampedPerAxis) {
  WindowPolicyOptions o;  // 3 sigma, [1, 12.5] m, [2, 15] deg
  WindowExtent w = searchWindowFor(priorWithSigma(0.1, 0.001), o);
  EXPECT_DOUBLE_EQ(w.half_x_m, o.min_half_xy_m);
  EXPECT_DOUBLE_EQ(w.half_heading_rad, o.min_half_heading_rad);
  w = searchWindowFor(priorWithSigma(1.0, 0.02), o);
  EXPECT_NEAR(w.half_x_m, 3.0, 1e-12);
  EXPECT_NEAR(w.half_y_m, 3.0, 1e-12);
  EXPECT_NEAR(w.half_heading_rad, 0.06, 1e-12);
  w = searchWindowFor(priorWithSigma(50.0, 1.0), o);
  EXPECT_DOUBLE_EQ(w.half_x_m, o.max_half_xy_m);
  EXPECT_DOUBLE_EQ(w.half_heading_rad, o.max_half_heading_rad);
  Prior anisotropic = priorWithSigma(1.0, 0.02);
  anisotropic.covariance_xyh(1, 1) = 0.25;  // 0.5 m in y
  w = searchWindowFor(anisotropic, o);
  EXPECT_NEAR(w.half_y_m, 1.5, 1e-12);
  Prior nan = priorWithSigma(kNaN, kNaN);
  w = searchWindowFor(nan, o);
  EXPECT_DOUBLE_EQ(w.half_x_m, o.max_half_xy_m);
  Prior wide = priorWithSigma(0.1, 0.001);
  wide.wide = true;
  w = searchWindowFor(wide, o);
  EXPECT_DOUBLE_EQ(w.half_x_m, o.wide_half_xy_m);
  EXPECT_DOUBLE_EQ(w.half_heading_rad, o.wide_half_heading_rad);
}

MatchResult goodResult() {
  MatchResult r;
  r.map_coverage = 0.9;
  r.log_likelihood_per_point = 0.5;
  r.covariance_xyh = Eigen::Vector3d(0.01, 0.01, 1e-5).asDiagonal();
  r.search.tx = 5;
  r.search.ty = 5;
  r.search.heading_index = 3;
  return r;
}

SearchWindow window10() {
  SearchWindow w;
  w.half_x = w.half_y = 5;
  w.half_h = 3;
  w.heading_step_rad = 0.01;
  return w;
}

TEST(AcceptMatch, EachRuleRejectsWithItsReason) {
  const AcceptancePolicyOptions o;
  EXPECT_TRUE(acceptMatch(goodResult(), window10(), o).accepted);

  MatchResult r = goodResult();
  r.map_coverage = 0.1;
  AcceptanceDecision d = acceptMatch(r, window10(), o);
  EXPECT_FALSE(d.accepted);
  EXPECT_NE(d.reason.find("map coverage"), std::string::npos) << d.reason;

  r = goodResult();
  r.log_likelihood_per_point = -4.5;
  d = acceptMatch(r, window10(), o);
  EXPECT_FALSE(d.accepted);
  EXPECT_NE(d.reason.find("log-likelihood"), std::string::npos) << d.reason;

  r = goodResult();
  r.covariance_xyh(0, 0) = 4.0;  // 2 m: a featureless stretch
  d = acceptMatch(r, window10(), o);
  EXPECT_NE(d.reason.find("ambiguous"), std::string::npos) << d.reason;

  r = goodResult();
  r.search.tx = 10;  // last translation of a +-5 cell window
  d = acceptMatch(r, window10(), o);
  EXPECT_NE(d.reason.find("edge (x"), std::string::npos) << d.reason;
  r = goodResult();
  r.search.heading_index = 0;
  d = acceptMatch(r, window10(), o);
  EXPECT_NE(d.reason.find("heading"), std::string::npos) << d.reason;
  AcceptancePolicyOptions no_edge = o;
  no_edge.reject_on_window_edge = false;
  EXPECT_TRUE(acceptMatch(r, window10(), no_edge).accepted);

  r = goodResult();
  r.pose.x = kNaN;
  EXPECT_FALSE(acceptMatch(r, window10(), o).accepted);

  // An uncertified match passes by default and is rejected, naming the failure, on request.
  r = goodResult();
  r.certificate.certified = false;
  r.certificate.failure = CertificateFailure::kAmbiguous;
  EXPECT_TRUE(acceptMatch(r, window10(), o).accepted);
  AcceptancePolicyOptions strict = o;
  strict.require_certificate = true;
  d = acceptMatch(r, window10(), strict);
  EXPECT_FALSE(d.accepted);
  EXPECT_EQ(d.reason, "uncertified: ambiguous");
  r.certificate.certified = true;
  r.certificate.failure = CertificateFailure::kNone;
  EXPECT_TRUE(acceptMatch(r, window10(), strict).accepted);

  // A wide or global window (a jump from the tracked pose) needs the certificate by default.
  r.certificate.certified = false;
  r.certificate.failure = CertificateFailure::kBudget;
  d = acceptMatch(r, window10(), o, /*wide=*/true);
  EXPECT_FALSE(d.accepted);
  EXPECT_EQ(d.reason, "uncertified in a wide window: budget");
  r.global = true;
  EXPECT_EQ(acceptMatch(r, window10(), o, true).reason, "uncertified in a global window: budget");
  AcceptancePolicyOptions lenient = o;
  lenient.require_certificate_wide = false;
  EXPECT_TRUE(acceptMatch(r, window10(), lenient, true).accepted);
  r.certificate.failure = CertificateFailure::kDisabled;  // no proof asked for: not applied
  EXPECT_TRUE(acceptMatch(r, window10(), o, true).accepted);
  r.certificate.certified = true;
  r.certificate.failure = CertificateFailure::kNone;
  EXPECT_TRUE(acceptMatch(r, window10(), o, true).accepted);
}

bool spd(const Matrix6d& c) {
  Eigen::SelfAdjointEigenSolver<Matrix6d> e(c);
  return c.allFinite() && (c - c.transpose()).cwiseAbs().maxCoeff() < 1e-15 &&
         e.eigenvalues().minCoeff() > 0.0;
}

TEST(PublishedPoseCovariance, SearchBlockScaledFlooredAndFixedSigmas) {
  PoseCovariancePolicyOptions o;
  o.search_covariance_scale = 2.0;
  Eigen::Matrix3d s;
  s << 0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 1e-4;
  Matrix6d c = publishedPoseCovariance(s, o);
  EXPECT_TRUE(spd(c));
  EXPECT_NEAR(c(kStateX, kStateX), 0.08, 1e-12);
  EXPECT_NEAR(c(kStateY, kStateY), 0.18, 1e-12);
  EXPECT_NEAR(c(kStateX, kStateY), 0.02, 1e-12);
  EXPECT_NEAR(c(kStateYaw, kStateYaw), 2e-4, 1e-15);
  EXPECT_NEAR(c(kStateZ, kStateZ), o.sigma_z_m * o.sigma_z_m, 1e-15);
  EXPECT_NEAR(c(kStateRoll, kStateRoll), o.sigma_roll_pitch_rad * o.sigma_roll_pitch_rad, 1e-15);
  EXPECT_EQ(c(kStateX, kStateZ), 0.0);

  // Floors raise tiny variances, keeping the correlation coefficient.
  Eigen::Matrix3d tiny;
  tiny << 1e-8, 5e-9, 0, 5e-9, 1e-8, 0, 0, 0, 0;
  c = publishedPoseCovariance(tiny, PoseCovariancePolicyOptions());
  EXPECT_TRUE(spd(c));
  EXPECT_NEAR(std::sqrt(c(kStateX, kStateX)), 0.03, 1e-9);
  EXPECT_NEAR(c(kStateX, kStateY) / c(kStateX, kStateX), 0.5, 1e-9);
  EXPECT_NEAR(std::sqrt(c(kStateYaw, kStateYaw)), 0.01, 1e-12);

  // Fixed mode and non-finite input use the fixed sigmas.
  PoseCovariancePolicyOptions fixed;
  fixed.use_search_covariance = false;
  c = publishedPoseCovariance(s, fixed);
  EXPECT_NEAR(c(kStateX, kStateX), fixed.fixed_sigma_xy_m * fixed.fixed_sigma_xy_m, 1e-15);
  Eigen::Matrix3d bad = s;
  bad(0, 0) = kNaN;
  c = publishedPoseCovariance(bad, PoseCovariancePolicyOptions());
  EXPECT_TRUE(spd(c));
}

TEST(PublishedPoseCovariance, UncertifiedMatchesGetTheUncertifiedFloors) {
  PoseCovariancePolicyOptions o;
  Eigen::Matrix3d s;
  s << 0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 1e-4;
  const Matrix6d certified = publishedPoseCovariance(s, o, true);
  const Matrix6d uncertified = publishedPoseCovariance(s, o, false);
  EXPECT_TRUE(spd(uncertified));
  EXPECT_NEAR(certified(kStateX, kStateX), 0.04, 1e-12);
  EXPECT_NEAR(std::sqrt(uncertified(kStateX, kStateX)), o.uncertified_min_sigma_xy_m, 1e-9);
  EXPECT_NEAR(std::sqrt(uncertified(kStateY, kStateY)), o.uncertified_min_sigma_xy_m, 1e-9);
  EXPECT_NEAR(std::sqrt(uncertified(kStateYaw, kStateYaw)), o.uncertified_min_sigma_yaw_rad, 1e-9);
  // z, roll and pitch are not the search's: unchanged.
  EXPECT_EQ(certified(kStateZ, kStateZ), uncertified(kStateZ, kStateZ));
  // A search covariance already wider than the floors stays as it is.
  const Eigen::Matrix3d wide = Eigen::Vector3d(4.0, 4.0, 0.01).asDiagonal();
  EXPECT_NEAR(publishedPoseCovariance(wide, o, false)(kStateX, kStateX), 4.0, 1e-12);
}

OdometrySample odomAt(double t, double vx) {
  OdometrySample s;
  s.stamp_s = t;
  s.odom_T_base.translation() = Eigen::Vector3d(vx * t, 0, 0);
  s.linear_mps = Eigen::Vector3d(vx, 0, 0);
  return s;
}

TEST(OdometryBuffer, InterpolatesExtrapolatesAndRestartsWhenTimeGoesBack) {
  OdometryBuffer b(5.0, 0.3, 1.0);
  EXPECT_FALSE(b.poseAt(0.0).ok());
  for (int k = 0; k <= 100; ++k) {
    EXPECT_EQ(b.add(odomAt(k * 0.01, 10.0)), OdometryBuffer::AddResult::kAdded);
  }
  auto p = b.poseAt(0.555);
  ASSERT_TRUE(p.ok()) << p.error();
  EXPECT_NEAR(p->translation().x(), 5.55, 1e-9);
  p = b.poseAt(1.2);  // 0.2 s past the newest: extrapolated with the twist
  ASSERT_TRUE(p.ok());
  EXPECT_NEAR(p->translation().x(), 12.0, 1e-9);
  EXPECT_FALSE(b.poseAt(1.5).ok());
  EXPECT_FALSE(b.poseAt(-0.5).ok());
  auto tw = b.twistAt(0.5, 0.05);
  ASSERT_TRUE(tw.ok());
  EXPECT_NEAR(tw->linear_mps.x(), 10.0, 1e-12);
  EXPECT_FALSE(b.twistAt(3.0, 0.5).ok());
  EXPECT_EQ(b.add(odomAt(0.95, 10.0)), OdometryBuffer::AddResult::kDroppedOutOfOrder);
  EXPECT_EQ(b.add(odomAt(-20.0, 10.0)), OdometryBuffer::AddResult::kTimeWentBackwards);
  EXPECT_EQ(b.size(), 1u);
}

PosteriorEstimate posterior(double t, double x, double sigma) {
  PosteriorEstimate p;
  p.stamp_s = t;
  p.map_T_base.translation() = Eigen::Vector3d(x, 0, 0);
  p.covariance = Matrix6d::Identity() * sigma * sigma;
  p.twist.linear_mps = Eigen::Vector3d(10, 0, 0);
  return p;
}

TEST(PriorTracker, SelectsPriorsAndWidensAfterRejections) {
  LocalizationPolicyOptions o;
  o.relocalization.max_consecutive_rejections = 3;
  PriorTracker t(o);
  EXPECT_FALSE(t.priorAt(1.0, nullptr).valid());
  EXPECT_EQ(t.mode(), PriorMode::kNoPrior);

  // EKF posterior at t = 1.2 (x = 12), odometry at 10 m/s along x: carried back to a scan at
  // t = 1.0 it is at x = 10; window 3 sigma.
  OdometryBuffer odom;
  for (int k = 0; k <= 150; ++k) odom.add(odomAt(k * 0.01, 10.0));
  t.setPosterior(posterior(1.2, 12.0, 0.5));
  Prior p = t.priorAt(1.0, &odom);
  ASSERT_EQ(p.source, PriorSource::kEkf);
  EXPECT_TRUE(p.carried_by_odometry);
  EXPECT_NEAR(p.pose.x, 10.0, 1e-9);
  EXPECT_NEAR(p.age_s, -0.2, 1e-12);
  EXPECT_FALSE(p.wide);
  EXPECT_NEAR(searchWindowFor(p, o.window).half_x_m, 1.5, 1e-9);
  EXPECT_EQ(t.mode(), PriorMode::kTracking);
  // Without odometry: constant velocity with the posterior's twist.
  p = t.priorAt(1.0, nullptr);
  EXPECT_FALSE(p.carried_by_odometry);
  EXPECT_NEAR(p.pose.x, 10.0, 1e-9);

  // Consecutive rejections widen the window; an accepted match restores tracking.
  t.onRejected(1.0, t.priorAt(1.0, &odom));
  t.onRejected(1.0, t.priorAt(1.0, &odom));
  EXPECT_FALSE(t.priorAt(1.0, &odom).wide);
  t.onRejected(1.0, t.priorAt(1.0, &odom));
  EXPECT_EQ(t.mode(), PriorMode::kRelocalizing);
  p = t.priorAt(1.0, &odom);
  EXPECT_TRUE(p.wide);
  EXPECT_EQ(p.source, PriorSource::kEkf);
  Pose6 matched;
  matched.x = 10.05;
  t.onAccepted(1.0, matched, Eigen::Matrix3d::Identity() * 0.01, p);
  EXPECT_EQ(t.mode(), PriorMode::kTracking);
  EXPECT_FALSE(t.priorAt(1.0, &odom).wide);
  EXPECT_EQ(t.consecutiveRejections(), 0);

  // Explicit pose: wide around it until a match is accepted; configured (NaN stamp) is not
  // carried.
  Pose6 click;
  click.x = 50.0;
  t.setExplicitPose(click, kNaN, PriorSource::kConfigured, false);
  p = t.priorAt(1.3, &odom);
  EXPECT_EQ(p.source, PriorSource::kConfigured);
  EXPECT_TRUE(p.wide);
  EXPECT_FALSE(p.z_known);
  EXPECT_NEAR(p.pose.x, 50.0, 1e-12);
  t.setExplicitPose(click, 1.0, PriorSource::kInitialPose, true);
  p = t.priorAt(1.3, &odom);  // carried 0.3 s at 10 m/s
  EXPECT_EQ(p.source, PriorSource::kInitialPose);
  EXPECT_NEAR(p.pose.x, 53.0, 1e-9);
  // A match searched around an older prior does not cancel the pending explicit pose.
  const Prior older = p;
  t.setExplicitPose(click, 1.0, PriorSource::kInitialPose, true);
  t.onAccepted(1.3, matched, Eigen::Matrix3d::Identity() * 0.01, older);
  p = t.priorAt(1.3, &odom);
  EXPECT_EQ(p.source, PriorSource::kInitialPose);
  EXPECT_EQ(p.explicit_generation, older.explicit_generation + 1);
  // Its own match accepted: tracking on the EKF again (whose posterior, carried to 1.3 s at
  // x = 13, agrees with the match: after a jump a disagreeing one is not used).
  Pose6 found;
  found.x = 13.0;
  t.onAccepted(1.3, found, Eigen::Matrix3d::Identity() * 0.01, p);
  EXPECT_EQ(t.priorAt(1.3, &odom).source, PriorSource::kEkf);

  t.requestRelocalization();
  EXPECT_TRUE(t.priorAt(1.3, &odom).wide);
  t.reset();
  EXPECT_FALSE(t.priorAt(1.3, &odom).valid());
}

// A stale initial pose (the vehicle already far from it): the searches around it follow the
// odometry, so the offset stays what it was, and after lost_after_wide_rejections rejected wide
// windows the global window is searched around it.
TEST(PriorTracker, ARejectedExplicitPoseFollowsTheOdometryAndIsLostAfterWideRejections) {
  LocalizationPolicyOptions o;
  o.relocalization.lost_after_wide_rejections = 3;
  o.relocalization.lost_after_rejections = 0;
  PriorTracker t(o);
  // 10 m/s along x over 30 s, in a buffer of 10 s (as the matcher keeps).
  OdometryBuffer odom(10.0);
  Pose6 given;
  given.x = 100.0;
  t.setExplicitPose(given, kNaN, PriorSource::kConfigured, true);
  // Scans 4 s apart (a wide search around the wrong centre takes seconds). The configured pose is
  // the pose of the first scan searched around it, then it moves with the vehicle.
  const double scans[] = {5.0, 9.0, 13.0, 17.0, 21.0, 25.0};
  int k = 0;
  for (int i = 0; i < 4; ++i) {
    const double ts = scans[i];
    for (; k * 0.01 <= ts + 1e-9; ++k) odom.add(odomAt(k * 0.01, 10.0));
    const Prior p = t.priorAt(ts, &odom);
    ASSERT_EQ(p.source, PriorSource::kConfigured) << ts;
    EXPECT_NEAR(p.pose.x, 100.0 + 10.0 * (ts - scans[0]), 1e-6) << ts;
    EXPECT_EQ(p.carried_by_odometry, i > 0) << ts;
    EXPECT_TRUE(p.wide);
    // Wide windows rejected three times: lost, the global window around the carried pose.
    EXPECT_EQ(p.lost, i >= 3) << ts;
    EXPECT_EQ(t.mode(), i >= 3 ? PriorMode::kLost : PriorMode::kRelocalizing) << ts;
    t.onRejected(ts, p);
  }
  // A global window rejected: still lost, still carried, the next global window widened.
  for (; k * 0.01 <= scans[4] + 1e-9; ++k) odom.add(odomAt(k * 0.01, 10.0));
  Prior p = t.priorAt(scans[4], &odom);
  EXPECT_TRUE(p.lost);
  EXPECT_NEAR(p.pose.x, 100.0 + 10.0 * (scans[4] - scans[0]), 1e-6);
  EXPECT_NEAR(p.wide_window.half_x_m, o.window.global_max_half_xy_m * o.window.global_widen_factor,
              1e-9);
  // A match of an older explicit pose does not re-anchor a newer one.
  const Prior older = p;
  Pose6 clicked;
  clicked.x = -5.0;
  t.setExplicitPose(clicked, scans[4], PriorSource::kInitialPose, true);
  EXPECT_EQ(t.mode(), PriorMode::kRelocalizing);
  t.onRejected(scans[4], older);
  EXPECT_NEAR(t.priorAt(scans[4], &odom).pose.x, -5.0, 1e-9);
  // Accepted: tracking; the wide count starts again.
  Pose6 matched;
  matched.x = -5.0;
  t.onAccepted(scans[4], matched, Eigen::Matrix3d::Identity() * 0.01, t.priorAt(scans[4], &odom));
  EXPECT_EQ(t.mode(), PriorMode::kTracking);
  t.requestRelocalization();
  t.onRejected(scans[4], t.priorAt(scans[4], &odom));
  EXPECT_EQ(t.mode(), PriorMode::kRelocalizing);
}

TEST(PriorTracker, PreviousMatchStaleEstimatesAndTheFuture) {
  LocalizationPolicyOptions o;
  PriorTracker t(o);
  Pose6 m;
  m.x = 3.0;
  t.onAccepted(10.0, m, Eigen::Matrix3d::Identity() * 0.01, Prior());
  // Fresh match (no posterior): previous_match with a sigma grown by its age.
  Prior p = t.priorAt(11.0, nullptr);
  ASSERT_EQ(p.source, PriorSource::kPreviousMatch);
  EXPECT_NEAR(p.covariance_xyh(0, 0), 0.01 + 1.0, 1e-9);
  EXPECT_FALSE(p.wide);
  // Stale (older than 2 s, within 30 s): wide window around it.
  p = t.priorAt(20.0, nullptr);
  EXPECT_EQ(p.source, PriorSource::kPreviousMatch);
  EXPECT_TRUE(p.wide);
  EXPECT_NEAR(p.pose.x, 3.0, 1e-12);
  // Too old: nothing. From the future (the other side of a looping bag): nothing.
  EXPECT_FALSE(t.priorAt(100.0, nullptr).valid());
  EXPECT_FALSE(t.priorAt(5.0, nullptr).valid());
  // A fresh posterior wins over the match.
  t.setPosterior(posterior(20.0, 7.0, 0.2));
  p = t.priorAt(20.1, nullptr);
  EXPECT_EQ(p.source, PriorSource::kEkf);
  EXPECT_NEAR(p.pose.x, 8.0, 1e-9);  // 0.1 s at 10 m/s
}

TEST(PriorTracker, CompletesPlanarPosesFromThePosterior) {
  PriorTracker t{LocalizationPolicyOptions()};
  Pose6 planar;
  planar.x = 5.0;
  planar.yaw = 1.0;
  bool z_known = true;
  Pose6 full = t.completePlanarPose(planar, nullptr, &z_known);
  EXPECT_FALSE(z_known);
  EXPECT_EQ(full.z, 0.0);
  PosteriorEstimate e = posterior(1.0, 4.0, 0.1);
  e.map_T_base.translation().z() = 2.5;
  e.map_T_base.linear() = toIsometry(Pose6{0, 0, 0, 0.02, -0.03, 0.4}).linear();
  t.setPosterior(e);
  full = t.completePlanarPose(planar, nullptr, &z_known);
  EXPECT_TRUE(z_known);
  EXPECT_NEAR(full.z, 2.5, 1e-12);
  EXPECT_NEAR(full.roll, 0.02, 1e-9);
  EXPECT_NEAR(full.pitch, -0.03, 1e-9);
  EXPECT_NEAR(full.yaw, 1.0, 1e-12);
  planar.x = 100.0;  // far from the posterior: its height does not apply
  full = t.completePlanarPose(planar, nullptr, &z_known);
  EXPECT_FALSE(z_known);
}

// ---- LocalizationFilter -------------------------------------------------------------------

Matrix6d matchCov(double sxy) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << sxy * sxy, sxy * sxy, 0.01, 4e-4, 4e-4, 1e-5;
  return c;
}

TwistMeasurement still(double t) {
  TwistMeasurement m;
  m.stamp_s = t;  // zero covariance: the defaults apply
  return m;
}

TEST(LocalizationFilter, StartsFromAMatchAndUsesDefaultCovariances) {
  auto f = LocalizationFilter::create(EkfOptions(), FilterPolicyOptions());
  ASSERT_TRUE(f.ok()) << f.error();
  EXPECT_FALSE(f->active());
  EXPECT_TRUE(f->addImu(ImuMeasurement()).empty());
  EXPECT_EQ(f->addTwist(still(0.0)).outcome, FuseOutcome::kRejectedNotInitialized);
  Pose6 p;
  p.x = 1.0;
  p.y = 2.0;
  p.yaw = 0.5;
  EXPECT_EQ(f->addMatch(1.0, p, matchCov(0.05)).outcome, FuseOutcome::kFused);
  EXPECT_TRUE(f->active());
  const auto events = f->takeEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, FilterEventKind::kInitializedFromMatch);
  // A twist with an all-zero covariance is fused with the default covariance.
  const FuseReport r = f->addTwist(still(1.01));
  EXPECT_EQ(r.outcome, FuseOutcome::kFused) << r.reason;
  ImuMeasurement imu;
  imu.stamp_s = 1.02;
  imu.has_angular_velocity = true;
  const auto imu_reports = f->addImu(imu);
  ASSERT_EQ(imu_reports.size(), 1u);
  EXPECT_EQ(imu_reports[0].outcome, FuseOutcome::kFused) << imu_reports[0].reason;
  auto s = f->stateAt(1.02);
  ASSERT_TRUE(s.ok());
  EXPECT_NEAR(s->x(kStateX), 1.0, 1e-3);

  FilterPolicyOptions no_init;
  no_init.initialize_from_match = false;
  auto g = LocalizationFilter::create(EkfOptions(), no_init);
  EXPECT_EQ(g->addMatch(1.0, p, matchCov(0.05)).outcome, FuseOutcome::kRejectedNotInitialized);
}

TEST(LocalizationFilter, ADelayedFirstMatchIsBroughtForwardWithTheKeptTwists) {
  auto f = LocalizationFilter::create(EkfOptions(), FilterPolicyOptions());
  ASSERT_TRUE(f.ok()) << f.error();
  // The vehicle drives along x at 10 m/s; INS twists arrive at 100 Hz from 0 to 1 s, and the
  // match of the scan stamped 0.5 s (x = 5 m) arrives after all of them.
  for (int k = 0; k <= 100; ++k) {
    TwistMeasurement m = still(0.01 * k);
    m.linear_mps.x() = 10.0;
    m.covariance.diagonal() << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
    EXPECT_EQ(f->addTwist(m).outcome, FuseOutcome::kRejectedNotInitialized);
  }
  Pose6 p;
  p.x = 5.0;
  ASSERT_TRUE(f->addMatch(0.5, p, matchCov(0.05)).fused());
  auto s = f->stateAt(1.0);
  ASSERT_TRUE(s.ok()) << s.error();
  // Without the replay of the kept twists the estimate would stay at 5 m (where the vehicle
  // was when the scan was taken) until new twists arrive.
  EXPECT_NEAR(s->x(kStateX), 10.0, 0.3);
  EXPECT_NEAR(s->x(kStateVx), 10.0, 0.5);
}

/// Mean |along-track error| of the filter just before each match, over the last half of a
/// 20 s straight drive at 13 m/s: 100 Hz INS twists with a 1% scale error reported at 1 mm/s,
/// exact matches every 0.1 s.
double leadBeforeMatches(const FilterPolicyOptions& o) {
  auto f = LocalizationFilter::create(EkfOptions(), o);
  EXPECT_TRUE(f.ok()) << f.error();
  const double v = 13.0;
  double sum = 0.0;
  int n = 0;
  for (int k = 0; k <= 2000; ++k) {
    const double t = 0.01 * k;
    if (k % 10 == 0) {
      if (k >= 1000) {
        auto s = f->stateAt(t - 1e-3);
        EXPECT_TRUE(s.ok());
        sum += std::abs(s->x(kStateX) - v * (t - 1e-3));
        ++n;
      }
      Pose6 p;
      p.x = v * t;
      f->addMatch(t, p, matchCov(0.03));
    }
    TwistMeasurement m = still(t + 0.005);
    m.linear_mps.x() = 1.01 * v;
    m.covariance.diagonal() << 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6;
    f->addTwist(m);
  }
  return sum / std::max(1, n);
}

TEST(LocalizationFilter, TwistSigmaFloorKeepsAScaleErrorFromLeadingTheMatches) {
  FilterPolicyOptions as_reported, floored;
  floored.twist_linear_min_sigma_mps = 0.01;
  floored.twist_linear_sigma_per_speed = 0.01;
  const double lead_reported = leadBeforeMatches(as_reported);
  const double lead_floored = leadBeforeMatches(floored);
  std::printf("mean along-track error before a match: %.1f mm as reported, %.1f mm floored\n",
              1e3 * lead_reported, 1e3 * lead_floored);
  EXPECT_LT(lead_floored, 0.7 * lead_reported);
  FilterPolicyOptions bad;
  bad.twist_linear_sigma_per_speed = -1.0;
  EXPECT_NE(bad.validate().find("twist_linear_sigma_per_speed"), std::string::npos);
}

TEST(LocalizationFilter, GateLockoutAndRelocalizeInflateTheCovariance) {
  FilterPolicyOptions o;
  o.gate_lockout_count = 3;
  auto f = LocalizationFilter::create(EkfOptions(), o);
  ASSERT_TRUE(f.ok());
  Pose6 p;
  ASSERT_TRUE(f->addMatch(0.0, p, matchCov(0.05)).fused());
  f->takeEvents();
  // Matches 5 m away with 5 cm sigma: gated; the third triggers the lockout.
  Pose6 far = p;
  far.x = 5.0;
  double t = 0.0;
  for (int i = 0; i < 2; ++i) {
    t += 0.1;
    f->addTwist(still(t));
    EXPECT_EQ(f->addMatch(t, far, matchCov(0.05)).outcome, FuseOutcome::kRejectedGate);
  }
  EXPECT_EQ(f->consecutiveGateRejections(), 2);
  t += 0.1;
  f->addTwist(still(t));
  EXPECT_EQ(f->addMatch(t, far, matchCov(0.05)).outcome, FuseOutcome::kRejectedGate);
  EXPECT_EQ(f->lockouts(), 1u);
  const auto events = f->takeEvents();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().kind, FilterEventKind::kGateLockout);
  const double sx = std::sqrt(f->ekf().state().P(kStateX, kStateX));
  EXPECT_GE(sx, o.relocalize_sigma_xy_m - 1e-9);
  // The next far match now passes the gate.
  t += 0.1;
  f->addTwist(still(t));
  EXPECT_EQ(f->addMatch(t, far, matchCov(0.05)).outcome, FuseOutcome::kFused);
  EXPECT_NEAR(f->ekf().state().x(kStateX), 5.0, 0.05);
  // relocalize() inflates on request.
  ASSERT_TRUE(f->relocalize(t).ok());
  EXPECT_GE(std::sqrt(f->ekf().state().P(kStateYaw, kStateYaw)), o.relocalize_sigma_yaw_rad - 1e-9);
}

TEST(LocalizationFilter, TimeGoingBackwardsStopsItAndAnInitialPoseRestartsIt) {
  auto f = LocalizationFilter::create(EkfOptions(), FilterPolicyOptions());
  ASSERT_TRUE(f.ok());
  Pose6 p;
  ASSERT_TRUE(f->addMatch(100.0, p, matchCov(0.05)).fused());
  for (int k = 1; k <= 10; ++k) f->addTwist(still(100.0 + 0.01 * k));
  const FuseReport r = f->addTwist(still(10.0));  // the bag looped
  EXPECT_EQ(r.outcome, FuseOutcome::kTimeWentBackwards);
  EXPECT_FALSE(f->active());
  EXPECT_EQ(f->stops(), 1u);
  EXPECT_FALSE(f->stateAt(10.0).ok());
  // A planar initial pose (z unknown) restarts it; x, y, yaw sigmas are raised to the
  // relocalization sigmas so a match across the matcher's wide window passes the gate.
  Pose6 click;
  click.x = 20.0;
  Matrix6d rviz = Matrix6d::Zero();
  rviz.diagonal() << 0.25, 0.25, 0, 0, 0, 0.0685;
  ASSERT_TRUE(f->setInitialPose(click, rviz, 10.5, false).ok());
  EXPECT_TRUE(f->active());
  const EkfState& s = f->ekf().state();
  EXPECT_NEAR(s.x(kStateX), 20.0, 1e-9);
  EXPECT_NEAR(std::sqrt(s.P(kStateX, kStateX)), FilterPolicyOptions().relocalize_sigma_xy_m, 1e-9);
  EXPECT_NEAR(std::sqrt(s.P(kStateZ, kStateZ)), FilterPolicyOptions().unknown_z_sigma_m, 1e-9);
  Matrix6d bad = rviz;
  bad(0, 0) = kNaN;
  EXPECT_FALSE(f->setInitialPose(click, bad, 11.0, true).ok());
}

}  // namespace
}  // namespace gmm_localization

namespace gmm_localization {
namespace {

TEST(ExplicitPoseWindow, OnlyACoarseFixWidensTheSearch) {
  WindowPolicyOptions o;
  o.global_max_half_xy_m = 40.0;
  // rviz's "2D Pose Estimate" covariance (0.5 m, 15 deg): the wide window, as before.
  EXPECT_FALSE(explicitPoseWindow(Eigen::Vector3d(0.25, 0.25, 0.0685).asDiagonal(), o));
  // A 10 m fix: 3 sigma in x and y, the wide heading range.
  auto w = explicitPoseWindow(Eigen::Vector3d(100.0, 25.0, 0.0685).asDiagonal(), o);
  ASSERT_TRUE(w);
  EXPECT_DOUBLE_EQ(w->half_x_m, 30.0);
  EXPECT_DOUBLE_EQ(w->half_y_m, 30.0);
  EXPECT_DOUBLE_EQ(w->half_heading_rad, o.wide_half_heading_rad);
  // Heading unknown (3 sigma >= 90 deg) at a precise position: the full turn in the wide window.
  w = explicitPoseWindow(Eigen::Vector3d(0.25, 0.25, 1.0).asDiagonal(), o);
  ASSERT_TRUE(w);
  EXPECT_DOUBLE_EQ(w->half_x_m, o.wide_half_xy_m);
  EXPECT_DOUBLE_EQ(w->half_heading_rad, M_PI);
  // Capped, and garbage variances give the wide window.
  w = explicitPoseWindow(Eigen::Vector3d(1e6, 1e6, 100.0).asDiagonal(), o);
  ASSERT_TRUE(w);
  EXPECT_DOUBLE_EQ(w->half_x_m, 40.0);
  EXPECT_FALSE(explicitPoseWindow(Eigen::Vector3d(NAN, 1.0, 1.0).asDiagonal(), o));
  EXPECT_FALSE(explicitPoseWindow(Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal(), o));
  o.global_max_half_xy_m = 5.0;  // below the wide window
  EXPECT_FALSE(o.validate().empty());
}

TEST(GlobalHalfExtent, WidensByTheFactorUpToTheWidestThenCycles) {
  WindowPolicyOptions o;  // 50 m, factor 1.4142, widest 100 m: 50, 70.7, 100 (99.998), 50, ...
  ASSERT_EQ(o.validate(), "");
  const double expected[] = {50.0, 70.71, 99.998, 50.0, 70.71, 99.998, 50.0};
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(globalHalfExtent(o, k), expected[k], 1e-3) << k;
  // The widest between two powers: capped there, one size of its own.
  o.global_widest_half_xy_m = 80.0;
  EXPECT_NEAR(globalHalfExtent(o, 1), 70.71, 1e-3);
  EXPECT_DOUBLE_EQ(globalHalfExtent(o, 2), 80.0);
  EXPECT_DOUBLE_EQ(globalHalfExtent(o, 3), 50.0);
  // Never widened: factor 1, or the widest not above the first.
  o.global_widen_factor = 1.0;
  for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(globalHalfExtent(o, k), 50.0) << k;
  o.global_widen_factor = 2.0;
  o.global_widest_half_xy_m = 50.0;
  for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(globalHalfExtent(o, k), 50.0) << k;
  // Validation names the keys.
  o.global_widest_half_xy_m = 40.0;  // below global_max_half_xy_m
  EXPECT_NE(o.validate().find("global_widest_half_xy_m"), std::string::npos);
  o.global_widest_half_xy_m = 100.0;
  o.global_widen_factor = 0.5;
  EXPECT_NE(o.validate().find("global_widen_factor"), std::string::npos);
}

}  // namespace
}  // namespace gmm_localization
