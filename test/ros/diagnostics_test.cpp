// The diagnostics helpers on diagnostic_updater (ros/diagnostics.h): how a task's own verdict and
// the standard rate and stamp checks combine in one status, and the silence wording of the
// console lines. No master: ros::Time runs on the wall clock.

#include "gmm_localization/ros/diagnostics.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace gmm_localization {
namespace node {
namespace {

using diagnostic_msgs::DiagnosticStatus;

std::string value(const diagnostic_updater::DiagnosticStatusWrapper& w, const std::string& key) {
  for (const auto& kv : w.values) {
    if (kv.key == key) return kv.value;
  }
  return "<none>";
}

TEST(StatusBuilder, TheFirstProblemNamesTheStatusAndTheLevelNeverDrops) {
  diagnostic_updater::DiagnosticStatusWrapper w;
  w.level = DiagnosticStatus::OK;
  StatusBuilder s(w);
  s.summary(DiagnosticStatus::OK, "map loaded");  // an OK message when none is set
  EXPECT_EQ(w.message, "map loaded");
  s.summary(DiagnosticStatus::WARN, "IMU dropout");
  s.summary(DiagnosticStatus::WARN, "no scan matches");  // same level: the first stays
  s.summary(DiagnosticStatus::OK, "fine");               // never lowers
  EXPECT_EQ(w.level, DiagnosticStatus::WARN);
  EXPECT_EQ(w.message, "IMU dropout");
  s.add("rate [Hz]", 2.5);
  s.add("running", true);
  EXPECT_EQ(value(w, "running"), "true");
}

TEST(StatusBuilder, MergeJoinsProblemsAndKeepsTheWorstLevel) {
  diagnostic_updater::DiagnosticStatusWrapper w;
  w.level = DiagnosticStatus::OK;
  StatusBuilder s(w);
  s.merge(DiagnosticStatus::OK, "Desired frequency met");  // an OK check adds nothing
  EXPECT_TRUE(w.message.empty());
  s.summary(DiagnosticStatus::WARN, "no messages on /velodyne_points for 6.0 s");
  s.merge(DiagnosticStatus::ERROR, "No events recorded.");
  EXPECT_EQ(w.level, DiagnosticStatus::ERROR);
  EXPECT_EQ(w.message, "no messages on /velodyne_points for 6.0 s; No events recorded.");
}

class FrequencyMonitorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ros::Time::init(); }
  static diagnostic_updater::DiagnosticStatusWrapper fill(FrequencyMonitor& m) {
    diagnostic_updater::DiagnosticStatusWrapper w;
    w.level = DiagnosticStatus::OK;
    StatusBuilder s(w);
    m.fill(s);
    return w;
  }
};

TEST_F(FrequencyMonitorTest, NoMessagesIsAnError) {
  FrequencyMonitor m(5.0, 20.0);
  ros::WallDuration(0.05).sleep();
  const auto w = fill(m);
  EXPECT_EQ(w.level, DiagnosticStatus::ERROR);
  EXPECT_EQ(w.message, "No events recorded.");
  EXPECT_EQ(value(w, "Latest timestamp delay"), "<none>");  // no stamps given: not checked
}

TEST_F(FrequencyMonitorTest, TheRateIsCheckedAgainstItsBounds) {
  FrequencyMonitor m(0.5, 2.0);
  for (int i = 0; i < 10; ++i) {  // 10 messages in about 0.1 s (under 4 s however slow)
    m.tick();
    ros::WallDuration(0.01).sleep();
  }
  const auto w = fill(m);
  EXPECT_EQ(w.level, DiagnosticStatus::WARN);
  EXPECT_EQ(w.message, "Frequency too high.");
  EXPECT_EQ(value(w, "Events in window"), "10");
}

TEST_F(FrequencyMonitorTest, OldAndFutureStampsAreErrors) {
  FrequencyMonitor m(0.0, std::numeric_limits<double>::infinity(), /*max_delay_s=*/5.0,
                     /*min_delay_s=*/-1.0);
  m.tick();
  m.stamp(ros::Time::now() - ros::Duration(0.1));  // fresh
  ros::WallDuration(0.02).sleep();
  auto w = fill(m);
  EXPECT_EQ(w.level, DiagnosticStatus::OK) << w.message;
  m.tick();
  m.stamp(ros::Time::now() - ros::Duration(60.0));  // a bag's stamps on the wall clock
  w = fill(m);
  EXPECT_EQ(w.level, DiagnosticStatus::ERROR);
  EXPECT_NE(w.message.find("Timestamps too far in past seen."), std::string::npos) << w.message;
  m.tick();
  m.stamp(ros::Time::now() + ros::Duration(10.0));
  w = fill(m);
  EXPECT_NE(w.message.find("Timestamps too far in future seen."), std::string::npos) << w.message;
}

TEST(SilenceText, SaysSinceWhen) {
  EXPECT_EQ(silenceText(true, 6.24), "for 6.2 s");
  EXPECT_EQ(silenceText(false, 5.0), "in the 5.0 s since start-up");
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
