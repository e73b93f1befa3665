// The first pose outside every search window: rejected scans around one explicit pose, none
// accepted, make it "stuck" and its console line due (the matcher's "publish /initialpose"
// warning).

#include "gmm_localization/core/localization/acquisition_watch.h"

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

AcquisitionWatchOptions options(int after) {
  AcquisitionWatchOptions o;
  o.warn_after_rejections = after;
  o.repeat_s = 15.0;
  return o;
}

TEST(AcquisitionWatch, RejectionsAroundOnePoseMakeItStuck) {
  AcquisitionWatch w(options(20));
  for (int i = 0; i < 19; ++i) w.onScan(1, MatchOutcome::kRejected, i < 15 ? 3.0 : 12.5);
  EXPECT_FALSE(w.stuck());
  EXPECT_FALSE(w.due(0.0));
  w.onScan(1, MatchOutcome::kRejected, 12.5);
  EXPECT_TRUE(w.stuck());
  EXPECT_EQ(w.rejections(), 20);
  EXPECT_DOUBLE_EQ(w.widestWindowM(), 12.5);
  EXPECT_TRUE(w.due(10.0));
  EXPECT_FALSE(w.due(11.0));  // throttled
  EXPECT_TRUE(w.due(25.0));   // repeat_s later
}

TEST(AcquisitionWatch, SkippedScansDoNotCount) {
  AcquisitionWatch w(options(3));
  w.onScan(1, MatchOutcome::kRejected, 3.0);
  for (int i = 0; i < 10; ++i) w.onScan(1, MatchOutcome::kSkipped, 0.0);  // no map yet
  w.onScan(1, MatchOutcome::kRejected, 3.0);
  EXPECT_FALSE(w.stuck());
  EXPECT_EQ(w.rejections(), 2);
}

TEST(AcquisitionWatch, AnAcceptedMatchEndsIt) {
  AcquisitionWatch w(options(3));
  for (int i = 0; i < 3; ++i) w.onScan(1, MatchOutcome::kRejected, 3.0);
  EXPECT_TRUE(w.stuck());
  w.onScan(1, MatchOutcome::kAccepted, 3.0);
  EXPECT_FALSE(w.stuck());
  EXPECT_FALSE(w.due(0.0));
  // Tracking (generation 0) afterwards: its rejections are not an acquisition problem.
  for (int i = 0; i < 10; ++i) w.onScan(0, MatchOutcome::kRejected, 1.0);
  EXPECT_FALSE(w.stuck());
}

TEST(AcquisitionWatch, ANewPoseStartsItsOwnCount) {
  AcquisitionWatch w(options(3));
  for (int i = 0; i < 5; ++i) w.onScan(1, MatchOutcome::kRejected, 12.5);
  EXPECT_TRUE(w.due(0.0));
  // The user gives a new /initialpose (generation 2): a fresh count, and a fresh line later.
  w.onScan(2, MatchOutcome::kRejected, 3.0);
  EXPECT_FALSE(w.stuck());
  EXPECT_EQ(w.rejections(), 1);
  EXPECT_DOUBLE_EQ(w.widestWindowM(), 3.0);
  w.onScan(2, MatchOutcome::kRejected, 3.0);
  w.onScan(2, MatchOutcome::kRejected, 3.0);
  EXPECT_TRUE(w.due(1.0));  // not held back by the first pose's line
}

TEST(AcquisitionWatch, WarnsWhenATrackingMatcherWouldRelocalize) {
  RelocalizationPolicyOptions r;
  r.max_consecutive_rejections = 5;
  r.lost_after_rejections = 15;
  EXPECT_EQ(acquisitionWarnAfter(r), 5);  // before the global search: it may not reach either
  r.max_consecutive_rejections = 0;
  EXPECT_EQ(acquisitionWarnAfter(r), 1);
}

}  // namespace
}  // namespace gmm_localization
