// Reading a localization bag for `evaluate` (src/tools/evaluate/evaluate_bag.h): a merged cloud
// becomes the ScanInput the matcher would build, with how its per-point times were read or why
// the reader refused them, so that a refused scan's deskew note gives the reader's reason and
// not "no per-point time field".
#include "evaluate/evaluate_bag.h"

#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>

#include "gmm_localization/ros/cloud_conversion.h"

namespace gmm_localization {
namespace eval {
namespace {

/// A merged cloud in `frame` with one per-point 'time' (float32 s after the stamp) per point.
sensor_msgs::PointCloud2 mergedCloud(const std::vector<float>& times,
                                     const std::string& frame = "base_link") {
  node::CloudData c;
  for (size_t i = 0; i < times.size(); ++i) {
    c.points.emplace_back(5.f + static_cast<float>(i), 1.f, 0.f);
  }
  c.time_s = times;
  c.label.assign(times.size(), 2);
  sensor_msgs::PointCloud2 msg;
  node::toMsg(c, msg);
  msg.header.stamp = ros::Time(1'700'000'000, 500'000'000);
  msg.header.frame_id = frame;
  return msg;
}

/// The deskew note the matcher gives the scan (skipped: no map, no prior; the note is set first).
std::string deskewNote(const ScanInput& scan) {
  auto processor = MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions());
  EXPECT_TRUE(processor.ok()) << processor.error();
  const MatchReport r = processor->process(ChunkMap(), scan, Prior(), nullptr, false);
  EXPECT_FALSE(r.deskewed);
  return r.deskew_note;
}

TEST(EvaluateBag, GoodTimesAreReadWithTheirSource) {
  auto s = scanFromCloud(mergedCloud({0.0f, 0.05f, 0.09f}), "base_link");
  ASSERT_TRUE(s) << s.error();
  EXPECT_DOUBLE_EQ(s->scan.stamp_s, 1'700'000'000.5);
  EXPECT_EQ(s->scan.points.size(), 3u);
  ASSERT_EQ(s->scan.time_s.size(), 3u);
  EXPECT_FLOAT_EQ(s->scan.time_s[1], 0.05f);
  EXPECT_EQ(s->scan.time_source, "'time' float32 relative seconds");
  EXPECT_EQ(s->scan.time_problem, "");
  EXPECT_EQ(s->label, std::vector<uint8_t>({2, 2, 2}));
}

TEST(EvaluateBag, RefusedTimesCarryTheReadersReasonIntoTheDeskewNote) {
  // Times 5 s after the stamp: refused by the reader, the scan kept without them.
  auto s = scanFromCloud(mergedCloud({5.0f, 5.05f, 5.09f}), "base_link");
  ASSERT_TRUE(s) << s.error();
  EXPECT_EQ(s->scan.points.size(), 3u);
  EXPECT_TRUE(s->scan.time_s.empty());
  EXPECT_EQ(s->scan.time_source, "");
  EXPECT_NE(s->scan.time_problem.find("per-point 'time' (float32) makes no sense"),
            std::string::npos)
      << s->scan.time_problem;
  EXPECT_EQ(deskewNote(s->scan), s->scan.time_problem);

  // Without a time field the note says so (the case the refusal was mistaken for).
  sensor_msgs::PointCloud2 untimed = mergedCloud({0.0f, 0.05f});
  node::CloudData c = node::fromMsg(untimed).value();
  c.time_s.clear();
  node::toMsg(c, untimed);
  auto u = scanFromCloud(untimed, "base_link");
  ASSERT_TRUE(u) << u.error();
  EXPECT_EQ(u->scan.time_problem, "");
  EXPECT_NE(deskewNote(u->scan).find("no per-point time field"), std::string::npos);
}

TEST(EvaluateBag, CloudsOutsideTheBaseFrameAndMalformedOnesAreRefused) {
  auto s = scanFromCloud(mergedCloud({0.0f}, "velodyne_0"), "base_link");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().find("frame 'velodyne_0'"), std::string::npos) << s.error();
  sensor_msgs::PointCloud2 broken = mergedCloud({0.0f});
  broken.data.pop_back();
  s = scanFromCloud(broken, "base_link");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().rfind("cloud: ", 0), 0u) << s.error();
}

TEST(EvaluateBag, TheBagVisitorHandsOverTheTimeRefusal) {
  const std::string path = ::testing::TempDir() + "evaluate_bag_test.bag";
  BagTopics topics;
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    const sensor_msgs::PointCloud2 cloud = mergedCloud({5.0f, 5.05f});
    bag.write(topics.cloud, cloud.header.stamp, cloud);
    nav_msgs::Odometry truth;
    truth.header.stamp = cloud.header.stamp;
    truth.header.frame_id = "map";
    truth.pose.pose.orientation.w = 1.0;
    bag.write(topics.ground_truth, truth.header.stamp, truth);
  }
  std::vector<LabelledScan> scans;
  BagVisitor v;
  v.scan = [&](LabelledScan&& s) { scans.push_back(std::move(s)); };
  auto stats = visitLocalizationBag(path, topics, v);
  std::remove(path.c_str());
  ASSERT_TRUE(stats) << stats.error();
  EXPECT_EQ(stats->scans, 1u);
  EXPECT_EQ(stats->skipped, 0u);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_TRUE(scans[0].scan.time_s.empty());
  EXPECT_NE(scans[0].scan.time_problem.find("makes no sense"), std::string::npos)
      << scans[0].scan.time_problem;
  EXPECT_DOUBLE_EQ(scans[0].record_time_s, 1'700'000'000.5);
}

}  // namespace
}  // namespace eval
}  // namespace gmm_localization
