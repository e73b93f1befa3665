// The rules that detect a kidnapped vehicle or a track gone wrong and hand it to the global
// search (match_policy.h, prior_tracker.h): the likelihood collapse of uncertified tracking
// matches, lost after consecutive collapses (the wide window skipped), and the posterior that
// is not trusted after a jump until it agrees with the matches again; and the filter's side:
// the matcher's mode widens its covariance so that the match that finds the vehicle is fused.
#include <gtest/gtest.h>

#include <cmath>

#include "gmm_localization/core/localization/localization_filter.h"
#include "gmm_localization/core/localization/match_policy.h"
#include "gmm_localization/core/localization/prior_tracker.h"

namespace gmm_localization {
namespace {

MatchResult result(double ll, bool certified) {
  MatchResult r;
  r.map_coverage = 0.9;
  r.log_likelihood_per_point = ll;
  r.covariance_xyh = Eigen::Vector3d(0.01, 0.01, 1e-5).asDiagonal();
  r.search.tx = r.search.ty = 5;
  r.search.heading_index = 3;
  r.certificate.certified = certified;
  r.certificate.failure = certified ? CertificateFailure::kNone : CertificateFailure::kAmbiguous;
  return r;
}

SearchWindow window() {
  SearchWindow w;
  w.half_x = w.half_y = 5;
  w.half_h = 3;
  w.heading_step_rad = 0.01;
  return w;
}

TEST(LikelihoodCollapse, RejectsAnUncertifiedTrackingMatchFarBelowTheRecentMedian) {
  const AcceptancePolicyOptions o;  // drop 1.0 nats
  const double recent = -0.4;
  // The kidnap rostest's numbers: -0.4 before, -2.2 after, uncertified.
  AcceptanceDecision d = acceptMatch(result(-2.2, false), window(), o, false, recent);
  EXPECT_FALSE(d.accepted);
  EXPECT_TRUE(d.likelihood_collapsed);
  EXPECT_NE(d.reason.find("likelihood collapsed"), std::string::npos) << d.reason;
  EXPECT_NE(d.reason.find("ambiguous"), std::string::npos) << d.reason;
  // Within the drop, certified, no reference yet, the rule off: accepted.
  EXPECT_TRUE(acceptMatch(result(-1.3, false), window(), o, false, recent).accepted);
  EXPECT_TRUE(acceptMatch(result(-2.2, true), window(), o, false, recent).accepted);
  EXPECT_TRUE(acceptMatch(result(-2.2, false), window(), o, false, NAN).accepted);
  AcceptancePolicyOptions off = o;
  off.max_likelihood_drop = 0.0;
  EXPECT_TRUE(acceptMatch(result(-2.2, false), window(), off, false, recent).accepted);
  // A disabled certificate proves nothing either way: not applied.
  MatchResult disabled = result(-2.2, false);
  disabled.certificate.failure = CertificateFailure::kDisabled;
  EXPECT_TRUE(acceptMatch(disabled, window(), o, false, recent).accepted);
  // Wide and global windows have their own rule (the certificate), not this one.
  AcceptancePolicyOptions lenient = o;
  lenient.require_certificate_wide = false;
  d = acceptMatch(result(-2.2, false), window(), lenient, true, recent);
  EXPECT_TRUE(d.accepted);
  EXPECT_FALSE(d.likelihood_collapsed);
  // Noted whatever rule rejects the match: here the window's edge.
  MatchResult edge = result(-2.2, false);
  edge.search.tx = 10;
  d = acceptMatch(edge, window(), o, false, recent);
  EXPECT_FALSE(d.accepted);
  EXPECT_NE(d.reason.find("edge"), std::string::npos) << d.reason;
  EXPECT_TRUE(d.likelihood_collapsed);
}

OdometrySample odomAt(double t, double vx) {
  OdometrySample s;
  s.stamp_s = t;
  s.odom_T_base.translation() = Eigen::Vector3d(vx * t, 0, 0);
  s.linear_mps = Eigen::Vector3d(vx, 0, 0);
  return s;
}

PosteriorEstimate posteriorAt(double t, double x) {
  PosteriorEstimate p;
  p.stamp_s = t;
  p.map_T_base = Eigen::Isometry3d::Identity();
  p.map_T_base.translation().x() = x;
  p.covariance = Matrix6d::Identity() * 1e-4;
  return p;
}

Pose6 poseX(double x) {
  Pose6 p;
  p.x = x;
  return p;
}

TEST(PriorTracker, CollapsesInARowMakeItLostAtOnceAndTheReferenceIsTheMedian) {
  LocalizationPolicyOptions o;
  o.relocalization.lost_after_collapses = 3;
  o.relocalization.max_consecutive_rejections = 100;  // only the collapses count here
  o.relocalization.lost_after_rejections = 0;
  o.acceptance.likelihood_history = 5;
  PriorTracker t(o);
  OdometryBuffer odom(10.0);
  for (int k = 0; k <= 100; ++k) odom.add(odomAt(k * 0.01, 0.0));
  t.setPosterior(posteriorAt(0.5, 0.0));
  Prior p = t.priorAt(0.5, &odom);
  ASSERT_EQ(p.source, PriorSource::kEkf);
  EXPECT_TRUE(std::isnan(p.recent_log_likelihood_per_point));
  // The median of the last 5 accepted: -0.5 (the -3 outlier and the oldest -9 do not move it).
  for (double ll : {-9.0, -0.4, -0.5, -3.0, -0.6, -0.3})
    t.onAccepted(0.5, poseX(0.0), Eigen::Matrix3d::Identity() * 1e-3, p, ll);
  p = t.priorAt(0.5, &odom);
  EXPECT_DOUBLE_EQ(p.recent_log_likelihood_per_point, -0.5);

  // Two collapses and a rejection for another reason: the count starts again.
  t.onRejected(0.6, p, Rejection::kLikelihoodCollapse);
  t.onRejected(0.7, p, Rejection::kLikelihoodCollapse);
  t.onRejected(0.8, p, Rejection::kOther);
  t.onRejected(0.9, p, Rejection::kLikelihoodCollapse);
  t.onRejected(1.0, p, Rejection::kLikelihoodCollapse);
  EXPECT_NE(t.mode(), PriorMode::kLost);
  t.onRejected(1.0, p, Rejection::kLikelihoodCollapse);
  EXPECT_EQ(t.mode(), PriorMode::kLost);
  EXPECT_TRUE(t.priorAt(1.0, &odom).lost);
  // A global search that finds nothing (rejected for another reason than a collapse) leaves it
  // lost: the collapses are not undone, the next search is a global one again.
  for (int k = 0; k < 3; ++k) {
    t.onRejected(1.0, t.priorAt(1.0, &odom), Rejection::kOther);
    EXPECT_EQ(t.mode(), PriorMode::kLost) << k;
    EXPECT_TRUE(t.priorAt(1.0, &odom).lost) << k;
  }

  // A global match found the vehicle: tracking, the reference restarts from that match.
  const Prior global = t.priorAt(1.0, &odom);
  t.onAccepted(1.0, poseX(50.0), Eigen::Matrix3d::Identity() * 1e-3, global, -0.1);
  EXPECT_EQ(t.mode(), PriorMode::kTracking);
  EXPECT_DOUBLE_EQ(t.priorAt(1.0, &odom).recent_log_likelihood_per_point, -0.1);
}

TEST(PriorTracker, ASearchAroundAPoseReplacedWhileItRanIsNotCounted) {
  // The global start sends a window's pose while the matcher's own global search around the
  // previous one still runs: that search's rejection must not widen the new pose's window nor
  // count towards losing it.
  LocalizationPolicyOptions o;
  o.relocalization.lost_after_wide_rejections = 1;
  PriorTracker t(o);
  OdometryBuffer odom(10.0);
  for (int k = 0; k <= 100; ++k) odom.add(odomAt(k * 0.01, 0.0));
  t.setExplicitPose(poseX(0.0), 0.5, PriorSource::kInitialPose, false);
  t.onRejected(0.5, t.priorAt(0.5, &odom));  // the wide window around it: lost
  ASSERT_EQ(t.mode(), PriorMode::kLost);
  const Prior running = t.priorAt(0.6, &odom);  // the global search around it starts
  ASSERT_TRUE(running.lost);
  t.setExplicitPose(poseX(100.0), 0.7, PriorSource::kInitialPose, false);
  t.onRejected(0.6, running);  // ... and ends after the new pose came
  EXPECT_EQ(t.globalMisses(), 0);
  EXPECT_EQ(t.mode(), PriorMode::kRelocalizing);
  const Prior next = t.priorAt(0.8, &odom);
  EXPECT_NEAR(next.pose.x, 100.0, 1e-9);
  EXPECT_FALSE(next.lost);
  t.onRejected(0.8, next);  // the new pose's own rejection counts
  EXPECT_EQ(t.mode(), PriorMode::kLost);
}

TEST(PriorTracker, AfterAJumpAPosteriorThatDisagreesIsNotUsedUntilItAgrees) {
  LocalizationPolicyOptions o;
  PriorTracker t(o);
  OdometryBuffer odom(10.0);
  for (int k = 0; k <= 300; ++k) odom.add(odomAt(k * 0.01, 0.0));
  t.setPosterior(posteriorAt(1.0, 0.0));
  t.requestRelocalization(/*global=*/true);
  const Prior lost = t.priorAt(1.0, &odom);
  ASSERT_TRUE(lost.lost);
  // The global match (50 m away) is accepted; the EKF has not fused it yet.
  t.onAccepted(1.0, poseX(50.0), Eigen::Matrix3d::Identity() * 1e-3, lost, -0.1);
  t.setPosterior(posteriorAt(1.2, 0.0));
  Prior p = t.priorAt(1.2, &odom);
  EXPECT_EQ(p.source, PriorSource::kPreviousMatch);
  EXPECT_NEAR(p.pose.x, 50.0, 1e-9);
  // Accepted matches carry on from there while the posterior still disagrees.
  t.onAccepted(1.2, poseX(50.0), Eigen::Matrix3d::Identity() * 1e-3, p, -0.2);
  t.setPosterior(posteriorAt(1.3, 0.0));
  EXPECT_EQ(t.priorAt(1.3, &odom).source, PriorSource::kPreviousMatch);
  // The EKF fused it: its posterior agrees (within jump_posterior_max_gap_m) and is used; once a
  // match searched around it is accepted, it is trusted as before.
  t.setPosterior(posteriorAt(1.4, 50.5));
  p = t.priorAt(1.4, &odom);
  EXPECT_EQ(p.source, PriorSource::kEkf);
  t.onAccepted(1.4, poseX(50.0), Eigen::Matrix3d::Identity() * 1e-3, p, -0.2);
  t.setPosterior(posteriorAt(1.5, 47.0));  // 3 m from the match: trusted again
  EXPECT_EQ(t.priorAt(1.5, &odom).source, PriorSource::kEkf);
  // Without a jump a posterior is never second-guessed.
  PriorTracker plain(o);
  plain.setPosterior(posteriorAt(1.0, 0.0));
  const Prior q = plain.priorAt(1.0, &odom);
  plain.onAccepted(1.0, poseX(30.0), Eigen::Matrix3d::Identity() * 1e-3, q, -0.1);
  plain.setPosterior(posteriorAt(1.1, 0.0));
  EXPECT_EQ(plain.priorAt(1.1, &odom).source, PriorSource::kEkf);
}

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

TEST(LocalizationFilter, TheMatcherLostWidensTheCovarianceSoTheMatchThatFindsTheVehicleIsFused) {
  EkfOptions e;
  e.history_length_s = 8.0;  // as config/ekf.yaml: a global match comes seconds late
  e.time_backwards_tolerance_s = 8.0;
  const FilterPolicyOptions o;
  auto f = LocalizationFilter::create(e, o);
  ASSERT_TRUE(f.ok()) << f.error();
  f->onMatcherMode(0.0, PriorMode::kLost);  // not running: nothing
  EXPECT_TRUE(f->takeEvents().empty());
  ASSERT_TRUE(f->addMatch(0.0, poseX(0.0), matchCov(0.05)).fused());
  double t = 0.0;
  // Twists at 100 Hz; while lost_from <= t, a status every 0.1 s says the matcher is lost (its
  // scans are skipped while the global search runs).
  double lost_from = 1e9;
  auto feed = [&](double until) {
    for (; t < until - 1e-9;) {
      t += 0.01;
      f->addTwist(still(t));
      const long k = std::lround(t * 100.0);
      if (t >= lost_from && k % 10 == 0) f->onMatcherMode(t, PriorMode::kLost);
    }
  };
  feed(1.0);
  f->takeEvents();
  // The vehicle is 50 m away: the filter, confident, refuses the match that says so.
  EXPECT_EQ(f->addMatch(1.0, poseX(50.0), matchCov(0.05)).outcome, FuseOutcome::kRejectedGate);
  auto sigma = [&](int i) { return std::sqrt(f->ekf().state().P(i, i)); };
  EXPECT_LT(sigma(kStateX), 1.0);

  f->onMatcherMode(1.0, PriorMode::kTracking);
  EXPECT_LT(sigma(kStateX), 1.0);
  f->onMatcherMode(1.1, PriorMode::kRelocalizing);
  EXPECT_GE(sigma(kStateX), o.relocalize_sigma_xy_m - 1e-9);
  EXPECT_GE(sigma(kStateYaw), o.relocalize_sigma_yaw_rad - 1e-9);
  f->onMatcherMode(1.2, PriorMode::kRelocalizing);  // the same mode: no second event
  auto events = f->takeEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, FilterEventKind::kMatcherRelocalizing);
  f->onMatcherMode(1.3, PriorMode::kLost);
  EXPECT_GE(sigma(kStateX), o.lost_sigma_xy_m - 1e-9);
  EXPECT_GE(sigma(kStateY), o.lost_sigma_xy_m - 1e-9);
  EXPECT_GE(sigma(kStateYaw), o.lost_sigma_yaw_rad - 1e-9);
  events = f->takeEvents();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, FilterEventKind::kMatcherLost);

  // The global search found it from the scan at 1.5 s; its pose comes 3.5 s later, after the
  // lost statuses of the scans skipped meanwhile. It is fused at its stamp, after the floor of
  // 1.3 s (which lets it through the gate) and before theirs, which keep the sigma up.
  lost_from = 1.55;
  feed(5.0);
  EXPECT_TRUE(f->takeEvents().empty());  // still lost: no new entry
  EXPECT_EQ(f->addMatch(1.5, poseX(50.0), matchCov(0.05)).outcome, FuseOutcome::kFused);
  EXPECT_NEAR(f->ekf().state().x(kStateX), 50.0, 0.2);
  EXPECT_GE(sigma(kStateX), o.lost_sigma_xy_m - 1e-9);
  // Tracking again: the next match collapses it.
  lost_from = 1e9;
  f->onMatcherMode(5.0, PriorMode::kTracking);
  EXPECT_EQ(f->addMatch(5.0, poseX(50.0), matchCov(0.05)).outcome, FuseOutcome::kFused);
  EXPECT_LT(sigma(kStateX), 1.0);
  EXPECT_NEAR(f->ekf().state().x(kStateX), 50.0, 0.1);
  // A floor older than both matches goes before them in time: they are fused again after it;
  // it is not the newest status, so no event.
  f->onMatcherMode(1.4, PriorMode::kLost);
  EXPECT_LT(sigma(kStateX), 1.0);
  EXPECT_NEAR(f->ekf().state().x(kStateX), 50.0, 0.1);
  EXPECT_TRUE(f->takeEvents().empty());
}

}  // namespace
}  // namespace gmm_localization
