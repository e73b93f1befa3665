// Scoring a recorded replay (`evaluate recorded`, src/tools/evaluate/evaluate_recorded.h) when
// the recording's messages are not the definitions this build reads: a MatchStatus from an
// older build (same type name, another md5) or another type on the status topic is counted and
// named, never skipped in silence; with no readable status at all the evaluation fails with
// that reason instead of reporting "the matcher never ran".
#include "evaluate/evaluate_recorded.h"

#include <cstdio>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <std_msgs/String.h>
#include <topic_tools/shape_shifter.h>

#include "gmm_localization/MatchStatus.h"

namespace gmm_localization {
namespace eval {
namespace {

const ros::Time kStart(1'700'000'000, 0);

/// A recording with 2 s of ground truth at 10 Hz and what `extra` writes.
template <typename Extra>
std::string recording(const std::string& name, const Extra& extra) {
  const std::string path = ::testing::TempDir() + name + ".bag";
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int i = 0; i <= 20; ++i) {
    nav_msgs::Odometry gt;
    gt.header.stamp = kStart + ros::Duration(0.1 * i);
    gt.header.frame_id = "map";
    gt.pose.pose.position.x = 0.5 * i;
    gt.pose.pose.orientation.w = 1.0;
    bag.write("/ground_truth/odom", gt.header.stamp, gt);
  }
  extra(bag);
  bag.close();
  return path;
}

/// A message on `topic` that claims to be a `datatype` of another definition (md5). (A bag
/// holds one definition per topic: rosbag writes every later message of the topic under the
/// first one's.)
void writeOlder(rosbag::Bag& bag, const std::string& topic, const ros::Time& t,
                const std::string& datatype = "gmm_localization/MatchStatus") {
  std_msgs::String body;  // any bytes: only the header's type and md5 are looked at first
  body.data = "a MatchStatus of an older build";
  const uint32_t size = ros::serialization::serializationLength(body);
  std::vector<uint8_t> buffer(size);
  ros::serialization::OStream out(buffer.data(), size);
  ros::serialization::serialize(out, body);
  topic_tools::ShapeShifter older;
  older.morph("0123456789abcdef0123456789abcdef", datatype, "string data\n", "");
  ros::serialization::IStream in(buffer.data(), size);
  older.read(in);
  bag.write(topic, t, older);
}

RecordedEvaluationConfig configFor(const std::string& bag) {
  RecordedEvaluationConfig c;
  c.bag = bag;
  return c;
}

TEST(EvaluateRecorded, StatusesOfAnOlderDefinitionFailWithTheReason) {
  const std::string bag = recording("older_status", [](rosbag::Bag& b) {
    for (int i = 0; i < 3; ++i)
      writeOlder(b, "/localization/status", kStart + ros::Duration(0.5 * i));
  });
  std::ostringstream log;
  const auto r = runRecordedEvaluation(configFor(bag), log);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("3 message(s) on /localization/status are an older or newer "
                           "definition of gmm_localization/MatchStatus (md5 "
                           "0123456789abcdef0123456789abcdef; this build reads md5 " +
                           std::string(ros::message_traits::MD5Sum<MatchStatus>::value()) + ")"),
            std::string::npos)
      << r.error();
  EXPECT_NE(r.error().find("Replay the source bag again with this build"), std::string::npos);
  std::remove(bag.c_str());
}

TEST(EvaluateRecorded, AnotherTypeOnTheStatusTopicIsNamed) {
  const std::string bag = recording("string_status", [](rosbag::Bag& b) {
    std_msgs::String s;
    s.data = "not a status";
    b.write("/localization/status", kStart, s);
  });
  std::ostringstream log;
  const auto r = runRecordedEvaluation(configFor(bag), log);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("1 message(s) on /localization/status are std_msgs/String, not "
                           "gmm_localization/MatchStatus"),
            std::string::npos)
      << r.error();
  std::remove(bag.c_str());
}

TEST(EvaluateRecorded, ReadableStatusesAreScoredAndUnreadableEkfMessagesNoted) {
  const std::string bag = recording("mixed_status", [](rosbag::Bag& b) {
    for (int i = 0; i < 4; ++i) {
      MatchStatus s;
      s.header.stamp = kStart + ros::Duration(0.5 * i);
      s.header.frame_id = "map";
      b.write("/localization/status", s.header.stamp, s);
    }
    writeOlder(b, "/localization/odometry", kStart + ros::Duration(1.9), "nav_msgs/Odometry");
  });
  std::ostringstream log;
  const auto r = runRecordedEvaluation(configFor(bag), log);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->matches.size(), 4u);
  bool noted = false, never_ran = false;
  for (const std::string& n : r->info.notes) {
    noted =
        noted || n.find(
                     "1 message(s) on /localization/odometry are an older or newer definition of "
                     "nav_msgs/Odometry") == 0;
    never_ran = never_ran || n.find("the matcher never ran") != std::string::npos;
  }
  EXPECT_TRUE(noted) << ::testing::PrintToString(r->info.notes);
  EXPECT_FALSE(never_ran);
  EXPECT_TRUE(r->ekf.empty());
  std::remove(bag.c_str());
}

}  // namespace
}  // namespace eval
}  // namespace gmm_localization
