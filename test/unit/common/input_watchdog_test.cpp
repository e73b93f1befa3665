// Which input is silent and since when, the rate of the others, and when a silent input's
// console line is due (the nodelets' "no messages on <topic>" warnings).

#include "gmm_localization/core/common/input_watchdog.h"

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

TEST(InputWatchdog, AnInputNeverHeardIsSilentFromStartOn) {
  InputWatchdog w(5.0, 30.0);
  const size_t imu = w.add("imu");
  const size_t odom = w.add("odom");
  EXPECT_EQ(imu, 0u);
  EXPECT_EQ(odom, 1u);
  w.start(100.0);
  w.heard(odom, 101.0);
  EXPECT_FALSE(w.silent(imu, 104.9));
  EXPECT_TRUE(w.due(104.9).empty());
  EXPECT_TRUE(w.silent(imu, 105.0));
  EXPECT_FALSE(w.everHeard(imu));
  EXPECT_DOUBLE_EQ(w.silentFor(imu, 105.5), 5.5);  // since start
  const auto due = w.due(105.5);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].input, imu);
  EXPECT_EQ(due[0].name, "imu");
  EXPECT_FALSE(due[0].ever_heard);
  EXPECT_DOUBLE_EQ(due[0].silent_for_s, 5.5);
  EXPECT_FALSE(w.silent(odom, 105.5));  // heard at 101
}

TEST(InputWatchdog, AnInputThatStopsIsSilentSinceItsLastMessage) {
  InputWatchdog w(5.0, 30.0);
  const size_t points = w.add("points");
  w.start(0.0);
  for (int i = 0; i <= 100; ++i) w.heard(points, 0.1 * i);  // 10 Hz until 10 s
  EXPECT_FALSE(w.silent(points, 14.9));
  EXPECT_TRUE(w.due(14.9).empty());
  const auto due = w.due(15.2);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_TRUE(due[0].ever_heard);
  EXPECT_NEAR(due[0].silent_for_s, 5.2, 1e-9);
  EXPECT_EQ(w.count(points), 101u);
}

TEST(InputWatchdog, TheLineRepeatsWhileSilentAndIsReArmedByAMessage) {
  InputWatchdog w(5.0, 30.0);
  const size_t imu = w.add("imu");
  w.start(0.0);
  EXPECT_EQ(w.due(5.0).size(), 1u);  // falls silent: at once
  EXPECT_TRUE(w.due(6.0).empty());   // throttled
  EXPECT_TRUE(w.due(34.9).empty());
  EXPECT_EQ(w.due(35.0).size(), 1u);  // repeat_s later
  w.heard(imu, 36.0);
  EXPECT_TRUE(w.due(40.0).empty());   // talking again
  EXPECT_EQ(w.due(41.0).size(), 1u);  // a new silence: at once, not 30 s after the last line
  EXPECT_TRUE(w.due(42.0).empty());
}

TEST(InputWatchdog, EachInputHasItsOwnThrottle) {
  InputWatchdog w(5.0, 30.0);
  const size_t a = w.add("a");
  const size_t b = w.add("b");
  w.start(0.0);
  w.heard(b, 3.0);
  const auto first = w.due(5.0);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].input, a);
  const auto second = w.due(8.0);  // b falls silent while a is throttled
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].input, b);
}

TEST(InputWatchdog, RateCountsTheLastWindow) {
  InputWatchdog w(5.0, 30.0, 5.0);
  const size_t imu = w.add("imu");
  w.start(0.0);
  for (int i = 0; i < 1000; ++i) w.heard(imu, 0.01 * i);  // 100 Hz for 10 s
  EXPECT_NEAR(w.rateHz(imu, 10.0), 100.0, 1.0);
  EXPECT_NEAR(w.rateHz(imu, 12.5), 50.0, 1.0);  // half of the window without messages
  EXPECT_DOUBLE_EQ(w.rateHz(imu, 20.0), 0.0);
}

TEST(InputWatchdog, AClockThatStepsBackDoesNotSilenceTheThrottle) {
  InputWatchdog w(5.0, 30.0);
  w.add("imu");
  w.start(100.0);
  EXPECT_EQ(w.due(106.0).size(), 1u);
  // The wall clock was set back (NTP): the line is not held back for 30 s of a time that went.
  w.start(0.0);
  EXPECT_EQ(w.due(6.0).size(), 1u);
}

TEST(InputWatchdog, AnUnwatchedInputKeepsItsRateButGetsNoLine) {
  InputWatchdog w(5.0, 30.0);
  const size_t matches = w.add("matches", /*watch_silence=*/false);
  w.start(0.0);
  w.heard(matches, 1.0);
  EXPECT_TRUE(w.silent(matches, 7.0));
  EXPECT_TRUE(w.due(7.0).empty());
  EXPECT_DOUBLE_EQ(w.rateHz(matches, 2.0), 0.2);
}

TEST(LineThrottle, DueAtOnceThenAtMostEveryPeriodAndAgainAfterAReset) {
  LineThrottle t(10.0);
  EXPECT_TRUE(t.due(100.0));
  EXPECT_FALSE(t.due(105.0));
  EXPECT_TRUE(t.due(110.0));
  t.reset();
  EXPECT_TRUE(t.due(111.0));
  EXPECT_FALSE(t.due(112.0));
  EXPECT_TRUE(t.due(50.0));  // the clock stepped back
}

}  // namespace
}  // namespace gmm_localization
