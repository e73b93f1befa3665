// The cloud merger's geometry (cloud_merger_assembly.h): extrinsics applied exactly, non-finite
// points dropped with their fields, times re-based to the set's stamp, fields kept only when
// every input has them, and no valid-looking times for the points of a sensor whose times the
// reader refused (or which has none): the merged cloud's reader refuses them in turn.
#include "gmm_localization/ros/cloud_merger_assembly.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "../unit/support/corridor_map.h"
#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/ros/matcher_outputs.h"
#include "support/corridor_match_status.h"

namespace gmm_localization {
namespace node {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

CloudData threePoints() {
  CloudData c;
  c.points = {{1.f, 0.f, 0.f}, {kNan, 0.f, 0.f}, {0.f, 2.f, -1.f}};
  c.time_s = {0.01f, 0.02f, 0.03f};
  c.intensity = {10.f, 20.f, 30.f};
  c.ring = {1, 2, 3};
  c.label = {0, 1, 2};
  return c;
}

Eigen::Isometry3d extrinsic() {
  // A roof-mounted sensor: 1.2 m forward, 0.5 m left, 1.9 m up, yawed 90 degrees.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1.2, 0.5, 1.9);
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

TEST(CloudMergerAssembly, TransformMovesPointsAndDropsNonFinite) {
  CloudData out;
  EXPECT_EQ(transformCloud(threePoints(), extrinsic(), out), 1u);
  ASSERT_EQ(out.points.size(), 2u);
  // (1, 0, 0) rotated by 90 degrees is (0, 1, 0), then translated.
  EXPECT_NEAR(out.points[0].x(), 1.2f, 1e-6f);
  EXPECT_NEAR(out.points[0].y(), 1.5f, 1e-6f);
  EXPECT_NEAR(out.points[0].z(), 1.9f, 1e-6f);
  // (0, 2, -1) -> (-2, 0, -1) + t.
  EXPECT_NEAR(out.points[1].x(), -0.8f, 1e-6f);
  EXPECT_NEAR(out.points[1].y(), 0.5f, 1e-6f);
  EXPECT_NEAR(out.points[1].z(), 0.9f, 1e-6f);
  // The fields of the dropped point went with it.
  EXPECT_EQ(out.time_s, std::vector<float>({0.01f, 0.03f}));
  EXPECT_EQ(out.intensity, std::vector<float>({10.f, 30.f}));
  EXPECT_EQ(out.ring, std::vector<uint16_t>({1, 3}));
  EXPECT_EQ(out.label, std::vector<uint8_t>({0, 2}));
}

TEST(CloudMergerAssembly, FieldOfTheWrongSizeIsLeftOut) {
  CloudData in = threePoints();
  in.ring.pop_back();
  CloudData out;
  transformCloud(in, Eigen::Isometry3d::Identity(), out);
  EXPECT_TRUE(out.ring.empty());
  EXPECT_EQ(out.intensity.size(), 2u);
}

MergeInput input(size_t sensor, int64_t stamp_ns, CloudData cloud) {
  MergeInput in;
  in.sensor = sensor;
  in.stamp_ns = stamp_ns;
  in.cloud = std::make_shared<CloudData>(std::move(cloud));
  return in;
}

TEST(CloudMergerAssembly, MergeRebasesTimesToTheEarliestStamp) {
  CloudData a, b;
  transformCloud(threePoints(), Eigen::Isometry3d::Identity(), a);
  b = a;
  MergeCycle cycle;
  cycle.stamp_ns = 1'000'000'000;
  cycle.inputs = {input(0, 1'000'000'000, a), input(2, 1'051'000'000, b)};
  const CloudData m = mergeCycle(cycle);
  ASSERT_EQ(m.points.size(), 4u);
  ASSERT_EQ(m.time_s.size(), 4u);
  EXPECT_FLOAT_EQ(m.time_s[0], 0.01f);
  EXPECT_FLOAT_EQ(m.time_s[1], 0.03f);
  EXPECT_NEAR(m.time_s[2], 0.061f, 1e-6f);
  EXPECT_NEAR(m.time_s[3], 0.081f, 1e-6f);
  EXPECT_EQ(m.ring, std::vector<uint16_t>({1, 3, 1, 3}));
  EXPECT_EQ(m.label.size(), 4u);
  EXPECT_EQ(m.points[2], a.points[0]);
}

TEST(CloudMergerAssembly, FieldsMissingInOneInput) {
  CloudData a, b;
  transformCloud(threePoints(), Eigen::Isometry3d::Identity(), a);
  b = a;
  b.time_s.clear();     // a sensor without per-point time: its points get NaN, not the offset
  b.intensity.clear();  // no intensity anywhere rather than invented values
  MergeCycle cycle;
  cycle.stamp_ns = 5'000'000'000;
  cycle.inputs = {input(0, 5'000'000'000, a), input(1, 5'020'000'000, b)};
  std::vector<UntimedInput> untimed;
  const CloudData m = mergeCycle(cycle, &untimed);
  ASSERT_EQ(m.time_s.size(), 4u);
  EXPECT_FLOAT_EQ(m.time_s[0], 0.01f);
  EXPECT_TRUE(std::isnan(m.time_s[2]));
  EXPECT_TRUE(std::isnan(m.time_s[3]));
  ASSERT_EQ(untimed.size(), 1u);
  EXPECT_EQ(untimed[0].sensor, 1u);
  EXPECT_FALSE(untimed[0].refused);
  EXPECT_NE(untimed[0].reason.find("no per-point time field"), std::string::npos);
  EXPECT_TRUE(m.intensity.empty());
  EXPECT_EQ(m.ring.size(), 4u);
}

TEST(CloudMergerAssembly, NoInputWithTimesGivesNoTimeField) {
  CloudData a;
  transformCloud(threePoints(), Eigen::Isometry3d::Identity(), a);
  a.time_s.clear();
  MergeCycle cycle;
  cycle.stamp_ns = 5'000'000'000;
  cycle.inputs = {input(0, 5'000'000'000, a), input(1, 5'020'000'000, a)};
  std::vector<UntimedInput> untimed;
  const CloudData m = mergeCycle(cycle, &untimed);
  EXPECT_EQ(m.points.size(), 4u);
  EXPECT_TRUE(m.time_s.empty());
  EXPECT_TRUE(untimed.empty());
}

// The merger's path for one sensor cloud: message -> reader -> output frame.
CloudData sensorCloud(const PointList& points, const std::vector<float>& times,
                      const ros::Time& stamp, const Eigen::Isometry3d& T) {
  CloudData c;
  c.points = points;
  c.time_s = times;
  sensor_msgs::PointCloud2 msg;
  toMsg(c, msg);
  msg.header.stamp = stamp;
  msg.header.frame_id = "velodyne";
  auto read = fromMsg(msg);
  EXPECT_TRUE(read) << (read ? "" : read.error());
  CloudData out;
  if (read) transformCloud(*read, T, out);
  return out;
}

CloudData sensorCloud(const std::vector<float>& times, const ros::Time& stamp) {
  PointList points;
  for (size_t i = 0; i < times.size(); ++i) {
    points.emplace_back(5.f + static_cast<float>(i), 1.f, -1.f);
  }
  return sensorCloud(points, times, stamp, extrinsic());
}

/// The merged cloud as the merger publishes it (CloudMerger::publish).
sensor_msgs::PointCloud2 published(const CloudData& merged, int64_t stamp_ns) {
  sensor_msgs::PointCloud2 msg;
  toMsg(merged, msg);
  msg.header.stamp.fromNSec(static_cast<uint64_t>(stamp_ns));
  msg.header.frame_id = "base_link";
  msg.is_dense = true;
  return msg;
}

/// The merged cloud as the matcher reads it.
CloudData publishedAndRead(const CloudData& merged, int64_t stamp_ns) {
  auto read = fromMsg(published(merged, stamp_ns));
  EXPECT_TRUE(read) << (read ? "" : read.error());
  return read ? *read : CloudData();
}

constexpr int64_t kStampNs = 1'700'000'000'000'000'000;

TEST(CloudMergerAssembly, GoodInputTimesSurviveTheMergedCloudsReader) {
  const ros::Time stamp0(1'700'000'000, 0), stamp1(1'700'000'000, 30'000'000);
  MergeCycle cycle;
  cycle.stamp_ns = kStampNs;
  cycle.inputs = {input(0, kStampNs, sensorCloud({0.0f, 0.05f}, stamp0)),
                  input(1, kStampNs + 30'000'000, sensorCloud({0.01f, 0.09f}, stamp1))};
  ASSERT_EQ(cycle.inputs[0].cloud->time_kind, PointTimeKind::kRelativeSeconds);
  std::vector<UntimedInput> untimed;
  const CloudData m = mergeCycle(cycle, &untimed);
  EXPECT_TRUE(untimed.empty());
  const CloudData read = publishedAndRead(m, kStampNs);
  EXPECT_EQ(read.time_kind, PointTimeKind::kRelativeSeconds);
  EXPECT_TRUE(read.time_problem.empty());
  ASSERT_EQ(read.time_s.size(), 4u);
  EXPECT_NEAR(read.time_s[0], 0.0f, 1e-6f);
  EXPECT_NEAR(read.time_s[1], 0.05f, 1e-6f);
  EXPECT_NEAR(read.time_s[2], 0.04f, 1e-6f);
  EXPECT_NEAR(read.time_s[3], 0.12f, 1e-6f);
}

TEST(CloudMergerAssembly, RefusedInputTimesMakeTheMergedCloudsReaderRefuseItsTimes) {
  const ros::Time stamp0(1'700'000'000, 0), stamp1(1'700'000'000, 30'000'000);
  // Sensor 1 publishes times 5 s after its stamp: refused by the reader.
  MergeCycle cycle;
  cycle.stamp_ns = kStampNs;
  cycle.inputs = {input(0, kStampNs, sensorCloud({0.0f, 0.05f}, stamp0)),
                  input(1, kStampNs + 30'000'000, sensorCloud({5.0f, 5.1f}, stamp1))};
  ASSERT_EQ(cycle.inputs[1].cloud->time_kind, PointTimeKind::kRefused);
  ASSERT_TRUE(cycle.inputs[1].cloud->time_s.empty());
  std::vector<UntimedInput> untimed;
  const CloudData m = mergeCycle(cycle, &untimed);
  // The merger reports the sensor with the reader's reason ...
  ASSERT_EQ(untimed.size(), 1u);
  EXPECT_EQ(untimed[0].sensor, 1u);
  EXPECT_TRUE(untimed[0].refused);
  EXPECT_NE(untimed[0].reason.find(cycle.inputs[1].cloud->time_problem), std::string::npos);
  EXPECT_NE(untimed[0].reason.find("makes no sense"), std::string::npos);
  // ... and the merged cloud's times are refused, not read as the offset alone.
  const CloudData read = publishedAndRead(m, kStampNs);
  EXPECT_EQ(read.points.size(), 4u);
  EXPECT_EQ(read.time_kind, PointTimeKind::kRefused);
  EXPECT_TRUE(read.time_s.empty());
  EXPECT_NE(read.time_problem.find("'time'"), std::string::npos) << read.time_problem;
  EXPECT_NE(read.time_problem.find("not finite for 2 of the 4 points"), std::string::npos)
      << read.time_problem;
}

TEST(CloudMergerAssembly, EveryInputRefusedStillGivesARefusedTimeField) {
  const ros::Time stamp(1'700'000'000, 0);
  MergeCycle cycle;
  cycle.stamp_ns = kStampNs;
  cycle.inputs = {input(0, kStampNs, sensorCloud({5.0f, 5.1f}, stamp))};
  std::vector<UntimedInput> untimed;
  const CloudData m = mergeCycle(cycle, &untimed);
  EXPECT_EQ(untimed.size(), 1u);
  const CloudData read = publishedAndRead(m, kStampNs);
  EXPECT_EQ(read.time_kind, PointTimeKind::kRefused);
  EXPECT_NE(read.time_problem.find("not finite"), std::string::npos) << read.time_problem;
}

TEST(CloudMergerAssembly, EmptyCycle) {
  MergeCycle cycle;
  cycle.inputs = {input(0, 0, CloudData())};
  const CloudData m = mergeCycle(cycle);
  EXPECT_TRUE(m.points.empty());
  EXPECT_TRUE(m.time_s.empty());
}

/// The status of matching the merged cloud on the corridor, driving at 10 m/s.
MatchStatus statusOf(const sensor_msgs::PointCloud2& msg) {
  BodyTwist twist;
  twist.linear_mps.x() = 10.0;
  return testing::corridorMatchStatus(msg, &twist);
}

TEST(CloudMergerAssembly, TheMatcherDeskewsAGoodMergeAndSaysWhyNotWhenAnInputIsRefused) {
  // The corridor scan seen by two sensors (alternate points), each sweeping over 0.1 s.
  const PointList scan = testing::corridorScan();
  PointList halves[2];
  std::vector<float> times[2];
  for (size_t i = 0; i < scan.size(); ++i) {
    halves[i % 2].push_back(scan[i]);
    times[i % 2].push_back(0.1f * static_cast<float>(i) / static_cast<float>(scan.size()));
  }
  const ros::Time stamp0(1'700'000'000, 500'000'000), stamp1(1'700'000'000, 520'000'000);
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  MergeCycle cycle;
  cycle.stamp_ns = static_cast<int64_t>(stamp0.toNSec());
  cycle.inputs = {
      input(0, static_cast<int64_t>(stamp0.toNSec()), sensorCloud(halves[0], times[0], stamp0, I)),
      input(1, static_cast<int64_t>(stamp1.toNSec()), sensorCloud(halves[1], times[1], stamp1, I))};
  MatchStatus s = statusOf(published(mergeCycle(cycle), cycle.stamp_ns));
  EXPECT_TRUE(s.deskewed) << s.deskew_note;
  EXPECT_EQ(s.point_times, "'time' float32 relative seconds");
  EXPECT_EQ(s.deskew_note, "");

  // Sensor 1's times 5 s after its stamp: refused by the reader, so NaN in the merged cloud.
  std::vector<float> late = times[1];
  for (float& t : late) t += 5.0f;
  cycle.inputs[1] =
      input(1, static_cast<int64_t>(stamp1.toNSec()), sensorCloud(halves[1], late, stamp1, I));
  s = statusOf(published(mergeCycle(cycle), cycle.stamp_ns));
  EXPECT_FALSE(s.deskewed);
  EXPECT_EQ(s.point_times, "");
  EXPECT_NE(s.deskew_note.find("per-point 'time' (float32) is not finite for " +
                               std::to_string(halves[1].size()) + " of the " +
                               std::to_string(scan.size()) + " points"),
            std::string::npos)
      << s.deskew_note;
  EXPECT_GT(s.search_points, 0u);  // matched all the same
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
