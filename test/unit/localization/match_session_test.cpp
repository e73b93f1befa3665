// MatchSession (core/localization/match_session.h), the session rules the matcher nodelet and
// LocalizerPipeline share, on synthetic inputs: time going backwards resets the tracker and
// re-arms the configured pose, the epoch discards a result begun before the reset, the scan
// queue drops its oldest entry at capacity (checked against a reference model on a seeded random
// sequence), and accepted / rejected outcomes drive the prior tracker.

#include "gmm_localization/core/localization/match_session.h"

#include <cmath>
#include <deque>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace {

Pose6 poseAt(double x, double y, double yaw) {
  Pose6 p;
  p.x = x;
  p.y = y;
  p.yaw = yaw;
  return p;
}

ScanInput scanAt(double stamp_s) {
  ScanInput s;
  s.stamp_s = stamp_s;
  s.points.assign(10, Eigen::Vector3f(1.f, 2.f, 0.f));
  s.time_s.assign(10, 0.05f);
  return s;
}

/// What MatchProcessor reports for an accepted match at the prior's pose moved by (dx, dy).
MatchReport acceptedReport(const ScanInput& scan, const MatchStart& start, double dx, double dy) {
  MatchReport r;
  r.stamp_s = scan.stamp_s;
  r.outcome = MatchOutcome::kAccepted;
  r.prior = start.prior;
  r.pose = start.prior.pose;
  r.pose.x += dx;
  r.pose.y += dy;
  Eigen::Matrix3d planar = Eigen::Vector3d(0.04, 0.09, 1e-4).asDiagonal();
  planar(0, 1) = planar(1, 0) = 0.01;
  r.covariance = poseCovarianceFromPlanar(planar);
  r.covariance(2, 2) = r.covariance(3, 3) = r.covariance(4, 4) = 0.5;
  return r;
}

MatchReport reportWith(const ScanInput& scan, const MatchStart& start, MatchOutcome outcome) {
  MatchReport r;
  r.stamp_s = scan.stamp_s;
  r.outcome = outcome;
  r.prior = start.prior;
  r.reason = outcome == MatchOutcome::kAccepted ? "" : "synthetic";
  return r;
}

using Session = MatchSession<int>;

/// Tracking: the configured pose (5, 5, 0) given, the match of `scan` around it accepted there.
bool trackAtConfiguredPose(Session& s, const ScanInput& scan) {
  s.setConfiguredPose(poseAt(5.0, 5.0, 0.0), true);
  const MatchStart start = s.beginMatch(scan);
  MatchReport r = acceptedReport(scan, start, 0.0, 0.0);
  return s.finishMatch(start.epoch, &r);
}

TEST(MatchSessionOptions, ValidateNamesTheKey) {
  MatchSessionOptions o;
  EXPECT_EQ(o.validate(), "");
  o.scan_queue_size = 0;
  EXPECT_NE(o.validate().find("scan_queue_size"), std::string::npos) << o.validate();
  o = MatchSessionOptions();
  o.odometry_buffer_s = 0.0;
  EXPECT_NE(o.validate().find("odometry_buffer_s"), std::string::npos) << o.validate();
  o = MatchSessionOptions();
  o.time_backwards_tolerance_s = NAN;
  EXPECT_NE(o.validate().find("time_backwards_tolerance_s"), std::string::npos);
}

TEST(MatchSession, AStampFarFromTheClockIsRefusedAndChangesNothing) {
  MatchSessionOptions o;
  o.max_scan_ahead_s = 2.0;
  o.max_scan_age_s = 10.0;
  Session s(o, LocalizationPolicyOptions());
  ASSERT_TRUE(s.arrive(100.0, 0, 100.05).refused.empty());
  // 1e5 s after the clock and 1e4 s before it: refused with the reason, not queued, no reset.
  const Session::Arrival ahead = s.arrive(100.1 + 1e5, 1, 100.15);
  EXPECT_NE(ahead.refused.find("after the clock"), std::string::npos) << ahead.refused;
  EXPECT_NE(ahead.refused.find("max_scan_ahead_s"), std::string::npos) << ahead.refused;
  const Session::Arrival behind = s.arrive(100.2 - 1e4, 2, 100.25);
  EXPECT_NE(behind.refused.find("before the clock"), std::string::npos) << behind.refused;
  EXPECT_NE(behind.refused.find("max_scan_age_s"), std::string::npos) << behind.refused;
  EXPECT_FALSE(behind.timeWentBackwards());
  EXPECT_EQ(s.waiting(), 1u);
  // The next good scan is not taken for time going backwards (the far-future stamp was not
  // remembered as the latest).
  const Session::Arrival good = s.arrive(100.3, 3, 100.35);
  EXPECT_TRUE(good.refused.empty());
  EXPECT_FALSE(good.timeWentBackwards());
  EXPECT_EQ(s.resets(), 0u);
  EXPECT_EQ(s.epoch(), 0u);
  // Within the limits (a late scan 9 s old, a clock 1.9 s behind the stamp): taken.
  EXPECT_TRUE(s.arrive(100.4, 4, 109.4).refused.empty());
  EXPECT_TRUE(s.arrive(111.3, 5, 109.4).refused.empty());
  // A clock that lags the data (a loaded host delivers /clock late): the newest INS sample
  // vouches for the stamp.
  OdometrySample sample;
  sample.stamp_s = 111.3;
  ASSERT_EQ(s.addOdometry(sample), OdometryBuffer::AddResult::kAdded);
  EXPECT_TRUE(s.arrive(113.0, 8, 105.0).refused.empty());
  EXPECT_FALSE(s.arrive(113.4, 9, 105.0).refused.empty());  // 2.1 s after the INS sample
  // No clock (NaN): no check; a non-finite stamp is refused in any case.
  EXPECT_TRUE(s.arrive(111.4 + 1e5, 6).refused.empty());
  EXPECT_FALSE(s.arrive(NAN, 7, 111.5).refused.empty());
  o.max_scan_age_s = -1.0;
  EXPECT_NE(o.validate().find("max_scan_age_s"), std::string::npos);
}

TEST(MatchSession, TimeGoingBackwardsResetsAndReArmsTheConfiguredPose) {
  MatchSessionOptions o;
  o.time_backwards_tolerance_s = 1.0;
  Session s(o, LocalizationPolicyOptions());
  const WindowExtent window{3.0, 3.0, 0.1};
  const Pose6 configured = poseAt(10.0, -5.0, 0.3);
  s.setConfiguredPose(configured, true, &window);

  ASSERT_FALSE(s.arrive(100.0, 0).timeWentBackwards());
  s.takeNext();
  const ScanInput first = scanAt(100.0);
  MatchStart start = s.beginMatch(first);
  EXPECT_EQ(start.prior.source, PriorSource::kConfigured);
  EXPECT_TRUE(start.prior.wide);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_x_m, 3.0);
  EXPECT_DOUBLE_EQ(start.prior.pose.x, 10.0);
  MatchReport r = acceptedReport(first, start, 0.5, 0.2);
  ASSERT_TRUE(s.finishMatch(start.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);

  // Within the tolerance: no reset.
  EXPECT_FALSE(s.arrive(100.5, 1).timeWentBackwards());
  EXPECT_FALSE(s.arrive(99.6, 2).timeWentBackwards());
  EXPECT_EQ(s.epoch(), 0u);
  EXPECT_EQ(s.resets(), 0u);
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);

  // 5.1 s back from the previous scan (99.6): the state of the other timeline goes.
  const Session::Arrival a = s.arrive(94.5, 3);
  EXPECT_TRUE(a.timeWentBackwards());
  EXPECT_NEAR(a.backwards_jump_s, 5.1, 1e-9);
  EXPECT_EQ(a.dropped, 2u);  // the two scans of the old timeline still waiting
  EXPECT_EQ(s.epoch(), 1u);
  EXPECT_EQ(s.resets(), 1u);
  EXPECT_EQ(s.tracker().mode(), PriorMode::kRelocalizing);
  ASSERT_EQ(s.waiting(), 1u);
  const Session::Next next = s.takeNext();
  EXPECT_EQ(next.item, 3);
  EXPECT_EQ(next.dropped_before, 2u);
  start = s.beginMatch(scanAt(94.5));
  EXPECT_EQ(start.prior.source, PriorSource::kConfigured);
  EXPECT_DOUBLE_EQ(start.prior.pose.x, configured.x);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_x_m, 3.0);
  EXPECT_EQ(start.epoch, 1u);

  // Without configured_pose_on_reset the session waits for a prior.
  o.configured_pose_on_reset = false;
  Session quiet(o, LocalizationPolicyOptions());
  quiet.setConfiguredPose(configured, true, &window);
  quiet.arrive(100.0, 0);
  EXPECT_TRUE(quiet.arrive(90.0, 1).timeWentBackwards());
  EXPECT_EQ(quiet.tracker().mode(), PriorMode::kNoPrior);
  EXPECT_FALSE(quiet.beginMatch(scanAt(90.0)).prior.valid());
}

/// Drives `s` from stamp t0 to t1 (10 Hz), every scan accepted at x = 10 m/s * stamp.
void driveAccepted(Session& s, double t0, double t1) {
  for (double t = t0; t <= t1 + 1e-9; t += 0.1) {
    s.arrive(t, 0);
    s.takeNext();
    const ScanInput scan = scanAt(t);
    MatchStart start = s.beginMatch(scan);
    MatchReport r = acceptedReport(scan, start, 0.0, 0.0);
    r.pose = poseAt(10.0 * t, 0.0, 0.0);
    ASSERT_TRUE(s.finishMatch(start.epoch, &r));
  }
}

TEST(MatchSession, TimeGoingBackwardsRecallsTheMatchRememberedAtTheNewStamp) {
  MatchSessionOptions o;
  o.time_backwards_tolerance_s = 1.0;
  const Pose6 configured = poseAt(-250.0, 0.0, 0.0);  // the launch's pose, far from the drive
  {
    Session s(o, LocalizationPolicyOptions());
    s.setConfiguredPose(configured, true);
    driveAccepted(s, 10.0, 30.0);
    // 17.97 s back (a looping bag): the match of the first pass at 12.0 s centres the search.
    ASSERT_TRUE(s.arrive(12.03, 1).timeWentBackwards());
    EXPECT_TRUE(s.lastResetRecalled());
    EXPECT_EQ(s.recalls(), 1u);
    s.takeNext();
    const MatchStart start = s.beginMatch(scanAt(12.03));
    EXPECT_EQ(start.prior.source, PriorSource::kPreviousMatch);
    EXPECT_TRUE(start.prior.wide);
    EXPECT_NEAR(start.prior.pose.x, 120.0, 1e-6);
    EXPECT_EQ(s.tracker().mode(), PriorMode::kRelocalizing);
    // Back before anything remembered: the configured pose, as without a history.
    ASSERT_TRUE(s.arrive(3.0, 2).timeWentBackwards());
    EXPECT_FALSE(s.lastResetRecalled());
    EXPECT_EQ(s.recalls(), 1u);
    s.takeNext();
    EXPECT_EQ(s.beginMatch(scanAt(3.0)).prior.source, PriorSource::kConfigured);
  }
  {
    // A short history forgets the first pass.
    LocalizationPolicyOptions policy;
    policy.relocalization.match_history_s = 1.0;
    Session s(o, policy);
    s.setConfiguredPose(configured, true);
    driveAccepted(s, 10.0, 30.0);
    EXPECT_LE(s.tracker().historySize(), 11u);
    ASSERT_TRUE(s.arrive(12.0, 1).timeWentBackwards());
    EXPECT_FALSE(s.lastResetRecalled());
    s.takeNext();
    EXPECT_EQ(s.beginMatch(scanAt(12.0)).prior.source, PriorSource::kConfigured);
  }
}

TEST(MatchSession, TheEpochDiscardsAResultBegunBeforeTimeWentBackwards) {
  Session s{MatchSessionOptions(), LocalizationPolicyOptions()};
  s.setConfiguredPose(poseAt(0.0, 0.0, 0.0), true);
  s.arrive(50.0, 0);
  s.takeNext();
  const ScanInput scan = scanAt(50.0);
  const MatchStart start = s.beginMatch(scan);
  // While it is matched, the bag loops.
  ASSERT_TRUE(s.arrive(20.0, 1).timeWentBackwards());
  MatchReport accepted = acceptedReport(scan, start, 0.1, 0.1);
  EXPECT_FALSE(s.finishMatch(start.epoch, &accepted));
  EXPECT_EQ(accepted.outcome, MatchOutcome::kSkipped);
  EXPECT_EQ(accepted.reason, "discarded: time went backwards during the match");
  // The tracker did not learn it: still searching the re-armed configured pose.
  EXPECT_EQ(s.tracker().mode(), PriorMode::kRelocalizing);
  EXPECT_EQ(s.beginMatch(scanAt(20.0)).prior.source, PriorSource::kConfigured);
  MatchReport rejected = reportWith(scan, start, MatchOutcome::kRejected);
  EXPECT_FALSE(s.finishMatch(start.epoch, &rejected));
  EXPECT_EQ(s.tracker().consecutiveRejections(), 0);
  // A match begun in the current epoch counts.
  const MatchStart now = s.beginMatch(scanAt(20.0));
  MatchReport fresh = acceptedReport(scanAt(20.0), now, 0.0, 0.0);
  EXPECT_TRUE(s.finishMatch(now.epoch, &fresh));
  EXPECT_EQ(fresh.outcome, MatchOutcome::kAccepted);
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);
}

TEST(MatchSession, TheQueueDropsTheOldestAtCapacity) {
  MatchSessionOptions o;
  o.scan_queue_size = 3;
  Session s(o, LocalizationPolicyOptions());
  EXPECT_EQ(s.queueCapacity(), 3u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(s.arrive(10.0 + 0.1 * i, i).dropped, i < 3 ? 0u : 1u) << i;
  }
  EXPECT_EQ(s.waiting(), 3u);
  Session::Next n = s.takeNext();
  EXPECT_EQ(n.item, 2);  // 0 and 1 went
  EXPECT_EQ(n.dropped_before, 2u);
  n = s.takeNext();
  EXPECT_EQ(n.item, 3);
  EXPECT_EQ(n.dropped_before, 0u);
  EXPECT_EQ(s.droppedTotal(), 2u);

  // A seeded random sequence of arrivals and takes against a reference model.
  for (const int capacity : {1, 2, 3, 7}) {
    o.scan_queue_size = capacity;
    Session q(o, LocalizationPolicyOptions());
    std::deque<int> model;
    uint32_t model_since = 0;
    uint64_t model_total = 0;
    std::mt19937 rng(1234 + capacity);
    std::bernoulli_distribution arrives(0.6);
    double stamp = 0.0;
    for (int step = 0, item = 0; step < 500; ++step) {
      if (arrives(rng) || model.empty()) {
        stamp += 0.1;
        size_t dropped = 0;
        if (static_cast<int>(model.size()) == capacity) {
          model.pop_front();
          dropped = 1;
        }
        model.push_back(item);
        model_since += dropped;
        model_total += dropped;
        ASSERT_EQ(q.arrive(stamp, item++).dropped, dropped) << "capacity " << capacity;
      } else {
        ASSERT_TRUE(q.hasWaiting());
        const Session::Next next = q.takeNext();
        ASSERT_EQ(next.item, model.front()) << "capacity " << capacity << " step " << step;
        ASSERT_EQ(next.dropped_before, model_since);
        model.pop_front();
        model_since = 0;
      }
      ASSERT_EQ(q.waiting(), model.size());
    }
    EXPECT_EQ(q.droppedTotal(), model_total);
    EXPECT_GT(model_total, 0u);
  }
}

TEST(MatchSession, AcceptedAndRejectedOutcomesDriveTheTracker) {
  LocalizationPolicyOptions policy;
  policy.relocalization.max_consecutive_rejections = 2;
  Session s(MatchSessionOptions(), policy);
  s.setConfiguredPose(poseAt(5.0, 5.0, 0.0), true);
  const ScanInput a = scanAt(10.0);
  MatchStart start = s.beginMatch(a);
  MatchReport r = acceptedReport(a, start, 0.4, -0.3);
  ASSERT_TRUE(s.finishMatch(start.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);
  // The next prior is the accepted match with the (x, y, yaw) block of its covariance.
  const ScanInput b = scanAt(10.0);
  start = s.beginMatch(b);
  EXPECT_EQ(start.prior.source, PriorSource::kPreviousMatch);
  EXPECT_FALSE(start.prior.wide);
  EXPECT_NEAR(start.prior.pose.x, 5.4, 1e-9);
  EXPECT_NEAR(start.prior.pose.y, 4.7, 1e-9);
  EXPECT_TRUE(start.prior.covariance_xyh.isApprox(planarCovariance(r.covariance), 1e-12));

  // Skipped scans (no map, no points) do not count; rejections do, up to the wide window.
  MatchReport skipped = reportWith(b, start, MatchOutcome::kSkipped);
  EXPECT_TRUE(s.finishMatch(start.epoch, &skipped));
  EXPECT_EQ(s.tracker().consecutiveRejections(), 0);
  MatchReport rejected = reportWith(b, start, MatchOutcome::kRejected);
  EXPECT_TRUE(s.finishMatch(start.epoch, &rejected));
  EXPECT_EQ(s.tracker().consecutiveRejections(), 1);
  EXPECT_FALSE(s.beginMatch(b).prior.wide);
  rejected = reportWith(b, start, MatchOutcome::kRejected);
  EXPECT_TRUE(s.finishMatch(start.epoch, &rejected));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kRelocalizing);
  start = s.beginMatch(b);
  EXPECT_TRUE(start.prior.wide);
  // An accepted match ends the relocalization.
  r = acceptedReport(b, start, 0.0, 0.0);
  EXPECT_TRUE(s.finishMatch(start.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);
  EXPECT_EQ(s.tracker().consecutiveRejections(), 0);
}

TEST(MatchSession, RejectionsInARowMakeTheLocalizationLostAndSearchTheGlobalWindow) {
  LocalizationPolicyOptions policy;
  policy.relocalization.max_consecutive_rejections = 2;
  policy.relocalization.lost_after_rejections = 4;
  policy.relocalization.lost_after_wide_rejections = 0;  // the count of all rejections alone
  policy.window.global_max_half_xy_m = 30.0;
  Session s(MatchSessionOptions(), policy);
  s.setConfiguredPose(poseAt(5.0, 5.0, 0.0), true);
  const ScanInput a = scanAt(10.0);
  MatchStart start = s.beginMatch(a);
  for (int k = 1; k <= 4; ++k) {
    EXPECT_FALSE(start.prior.lost) << k;
    MatchReport rejected = reportWith(a, start, MatchOutcome::kRejected);
    ASSERT_TRUE(s.finishMatch(start.epoch, &rejected));
    start = s.beginMatch(a);
  }
  EXPECT_EQ(s.tracker().mode(), PriorMode::kLost);
  EXPECT_STREQ(priorModeName(s.tracker().mode()), "lost");
  EXPECT_TRUE(start.prior.lost);
  EXPECT_TRUE(start.prior.wide);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_x_m, 30.0);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_heading_rad,
                   policy.window.global_max_half_heading_rad);
  EXPECT_DOUBLE_EQ(start.prior.pose.x, 5.0);  // around the same centre
  // The first accepted match ends it.
  MatchReport r = acceptedReport(a, start, 0.3, 0.0);
  ASSERT_TRUE(s.finishMatch(start.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);
  EXPECT_FALSE(s.beginMatch(a).prior.lost);
}

TEST(MatchSession, AGlobalSearchRequestedSearchesTheGlobalWindowUntilAMatchOfItIsAccepted) {
  LocalizationPolicyOptions policy;
  policy.window.global_max_half_xy_m = 40.0;
  Session s(MatchSessionOptions(), policy);
  EXPECT_NE(s.requestGlobalSearch().find("no pose to search around"), std::string::npos);
  const ScanInput a = scanAt(10.0);
  ASSERT_TRUE(trackAtConfiguredPose(s, a));
  const MatchStart before = s.beginMatch(a);  // a match under way when the request comes
  EXPECT_FALSE(before.prior.lost);
  EXPECT_EQ(s.requestGlobalSearch(), "");
  EXPECT_EQ(s.tracker().mode(), PriorMode::kLost);
  MatchStart start = s.beginMatch(a);
  EXPECT_TRUE(start.prior.lost);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_x_m, 40.0);
  // The match that started before does not end it; a rejected global one neither.
  MatchReport r = acceptedReport(a, before, 0.1, 0.0);
  ASSERT_TRUE(s.finishMatch(before.epoch, &r));
  EXPECT_TRUE(s.beginMatch(a).prior.lost);
  MatchReport rejected = reportWith(a, start, MatchOutcome::kRejected);
  ASSERT_TRUE(s.finishMatch(start.epoch, &rejected));
  start = s.beginMatch(a);
  EXPECT_TRUE(start.prior.lost);
  r = acceptedReport(a, start, 0.2, 0.0);
  ASSERT_TRUE(s.finishMatch(start.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);
  EXPECT_FALSE(s.beginMatch(a).prior.lost);
  // A new pose to search around replaces the request.
  EXPECT_EQ(s.requestGlobalSearch(), "");
  s.setConfiguredPose(poseAt(9.0, 5.0, 0.0), true);
  EXPECT_FALSE(s.beginMatch(a).prior.lost);
}

// A kidnapped vehicle's dead-reckoned centre drifts away from it at its own speed: each global
// search that finds nothing widens the next one (twice the area) up to the widest, then the
// cycle starts again (a search stopped at its budget may have missed a vehicle inside); an
// accepted match or a given pose starts again from global_max_half_xy_m.
TEST(MatchSession, EachGlobalSearchThatFindsNothingWidensTheNextOneInACycle) {
  LocalizationPolicyOptions policy;
  policy.window.global_max_half_xy_m = 50.0;
  policy.window.global_widen_factor = 1.5;
  policy.window.global_widest_half_xy_m = 100.0;
  Session s(MatchSessionOptions(), policy);
  const ScanInput a = scanAt(10.0);
  ASSERT_TRUE(trackAtConfiguredPose(s, a));
  MatchStart start;
  ASSERT_EQ(s.requestGlobalSearch(), "");
  auto rejectGlobal = [&]() {
    start = s.beginMatch(a);
    EXPECT_TRUE(start.prior.lost);
    EXPECT_DOUBLE_EQ(start.prior.wide_window.half_y_m, start.prior.wide_window.half_x_m);
    EXPECT_DOUBLE_EQ(start.prior.wide_window.half_heading_rad,
                     policy.window.global_max_half_heading_rad);
    EXPECT_DOUBLE_EQ(start.prior.pose.x, 5.0);  // the same centre
    MatchReport rejected = reportWith(a, start, MatchOutcome::kRejected);
    EXPECT_TRUE(s.finishMatch(start.epoch, &rejected));
    return start.prior.wide_window.half_x_m;
  };
  EXPECT_DOUBLE_EQ(rejectGlobal(), 50.0);
  EXPECT_DOUBLE_EQ(rejectGlobal(), 75.0);
  EXPECT_DOUBLE_EQ(rejectGlobal(), 100.0);  // 112.5 capped
  EXPECT_DOUBLE_EQ(rejectGlobal(), 50.0);   // and again
  EXPECT_DOUBLE_EQ(rejectGlobal(), 75.0);
  EXPECT_EQ(s.tracker().globalMisses(), 5);
  // Interim searches while a global one runs are not global ones: they never widen it.
  const MatchStart interim = s.beginMatch(a, /*global_available=*/false);
  EXPECT_TRUE(interim.prior.interim);
  MatchReport rejected = reportWith(a, interim, MatchOutcome::kRejected);
  ASSERT_TRUE(s.finishMatch(interim.epoch, &rejected));
  EXPECT_EQ(s.tracker().globalMisses(), 5);
  // Found: the next global search starts from global_max_half_xy_m again.
  start = s.beginMatch(a);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_x_m, 100.0);
  MatchReport r = acceptedReport(a, start, 0.0, 0.0);
  ASSERT_TRUE(s.finishMatch(start.epoch, &r));
  EXPECT_EQ(s.tracker().globalMisses(), 0);
  ASSERT_EQ(s.requestGlobalSearch(), "");
  EXPECT_DOUBLE_EQ(rejectGlobal(), 50.0);
  // So does a given pose.
  s.setConfiguredPose(poseAt(9.0, 5.0, 0.0), true);
  EXPECT_EQ(s.tracker().globalMisses(), 0);
}

TEST(MatchSession, WhileAGlobalSearchRunsALostPriorIsInterimOrSkipped) {
  LocalizationPolicyOptions policy;
  policy.window.global_max_half_xy_m = 40.0;
  policy.window.interim_half_xy_m = 1.5;
  policy.window.interim_half_heading_rad = 0.04;
  Session s(MatchSessionOptions(), policy);
  const ScanInput a = scanAt(10.0);
  ASSERT_TRUE(trackAtConfiguredPose(s, a));

  // Asked for (the estimate was fine): the other scans are searched in the interim window
  // around the same centre, with the certificate required; the global worker is busy.
  ASSERT_EQ(s.requestGlobalSearch(), "");
  const MatchStart global = s.beginMatch(a, /*global_available=*/true);
  EXPECT_TRUE(global.prior.lost);
  EXPECT_TRUE(global.global());
  EXPECT_FALSE(global.prior.interim);
  MatchStart interim = s.beginMatch(a, /*global_available=*/false);
  EXPECT_TRUE(interim.skip_reason.empty()) << interim.skip_reason;
  EXPECT_FALSE(interim.prior.lost);
  EXPECT_FALSE(interim.global());
  EXPECT_TRUE(interim.prior.interim);
  EXPECT_TRUE(interim.prior.wide);
  EXPECT_DOUBLE_EQ(interim.prior.wide_window.half_x_m, 1.5);
  EXPECT_DOUBLE_EQ(interim.prior.wide_window.half_y_m, 1.5);
  EXPECT_DOUBLE_EQ(interim.prior.wide_window.half_heading_rad, 0.04);
  EXPECT_DOUBLE_EQ(interim.prior.pose.x, global.prior.pose.x);
  EXPECT_DOUBLE_EQ(interim.prior.pose.y, global.prior.pose.y);
  // An accepted interim match answers its scan but does not end the global request.
  MatchReport r = acceptedReport(a, interim, 0.05, 0.0);
  ASSERT_TRUE(s.finishMatch(interim.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kLost);
  // A rejected interim window makes the localization lost by its rejections
  // (lost_after_wide_rejections 1): the scans are skipped while the global search runs.
  interim = s.beginMatch(a, false);
  MatchReport rejected = reportWith(a, interim, MatchOutcome::kRejected);
  ASSERT_TRUE(s.finishMatch(interim.epoch, &rejected));
  ASSERT_TRUE(s.tracker().lostByRejections());
  const MatchStart skipped = s.beginMatch(a, false);
  EXPECT_NE(skipped.skip_reason.find("global search of an earlier scan is running"),
            std::string::npos)
      << skipped.skip_reason;
  EXPECT_FALSE(skipped.global()) << "a skipped scan is not handed to the global worker";
  EXPECT_TRUE(s.beginMatch(a, true).global());
  // The global match accepted: tracking, no interim window even while a worker is busy.
  r = acceptedReport(a, global, 0.3, 0.0);
  ASSERT_TRUE(s.finishMatch(global.epoch, &r));
  EXPECT_EQ(s.tracker().mode(), PriorMode::kTracking);
  const MatchStart after = s.beginMatch(a, false);
  EXPECT_TRUE(after.skip_reason.empty());
  EXPECT_FALSE(after.prior.interim);
  EXPECT_FALSE(after.prior.lost);
}

TEST(MatchSession, TheMatchStartsWithTheDeskewTwistWhenConfigured) {
  MatchSessionOptions o;
  Session s(o, LocalizationPolicyOptions());
  OdometrySample sample;
  for (int i = 0; i <= 10; ++i) {
    sample.stamp_s = 10.0 + 0.02 * i;
    sample.odom_T_base.translation() = Eigen::Vector3d(0.1 * i, 0, 0);
    sample.linear_mps = Eigen::Vector3d(5.0, 0, 0);
    sample.angular_radps = Eigen::Vector3d(0, 0, 0.1);
    ASSERT_EQ(s.addOdometry(sample), OdometryBuffer::AddResult::kAdded);
  }
  const ScanInput scan = scanAt(10.1);
  const MatchStart start = s.beginMatch(scan);
  ASSERT_TRUE(start.twist.has_value());
  EXPECT_EQ(start.twistOrNull(), &*start.twist);
  EXPECT_DOUBLE_EQ(start.twist->linear_mps.x(), 5.0);
  EXPECT_FALSE(start.prior.valid());  // nothing to search around yet

  o.deskew = false;
  Session off(o, LocalizationPolicyOptions());
  off.addOdometry(sample);
  EXPECT_FALSE(off.beginMatch(scanAt(10.2)).twist.has_value());
  EXPECT_EQ(off.beginMatch(scanAt(10.2)).twistOrNull(), nullptr);
}

}  // namespace
}  // namespace gmm_localization
