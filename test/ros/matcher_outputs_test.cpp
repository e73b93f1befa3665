// The matcher's output messages from a MatchReport: status (never NaN, the prior's pose when
// rejected), the published pose and covariance, obstacle and classified clouds (Fig. 11
// fields), the traversal image (Fig. 9).
#include "gmm_localization/ros/matcher_outputs.h"

#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "../unit/support/corridor_map.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "support/corridor_match_status.h"

namespace gmm_localization {
namespace node {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

MatchReport acceptedReport() {
  MatchReport r;
  r.stamp_s = 10.0;
  r.outcome = MatchOutcome::kAccepted;
  r.prior.source = PriorSource::kEkf;
  r.prior.pose.x = 0.9;
  r.window = {1.5, 1.5, 0.05};
  r.input_points = 4;
  r.search_points = 3;
  r.has_result = true;
  r.result.pose.x = 1.0;
  r.result.pose.yaw = M_PI / 2;
  r.result.search.stats.evaluations = 1234;
  r.result.search.stats.exhaustive_poses = 100000;
  r.result.log_likelihood_per_point = 0.8;
  r.result.map_coverage = 0.95;
  r.pose = r.result.pose;
  r.covariance = Matrix6d::Identity() * 0.01;
  r.covariance(0, 1) = r.covariance(1, 0) = 0.002;
  r.correction_xy_m = 0.1;
  r.timing.search_s = 0.02;
  r.total_s = 0.05;
  r.points = {{1, 0, 0}, {2, 0, 1}, {std::nanf(""), 0, 0}, {0, 3, 2}};
  r.result.obstacles.label = {PointClass::kMap, PointClass::kObstacle, PointClass::kObstacle,
                              PointClass::kObstacle};
  r.result.obstacles.mahalanobis = {0.5f, 4.0f, kInf, kInf};
  r.result.obstacles.obstacles = 3;
  return r;
}

TEST(MatcherOutputs, StatusOfAnAcceptedAndARejectedScan) {
  MatchStatus s;
  toStatusMsg(acceptedReport(), "map", 0.12, 2, s);
  EXPECT_TRUE(s.accepted);
  EXPECT_EQ(s.reason, "");
  EXPECT_EQ(s.prior_source, "ekf");
  EXPECT_EQ(s.header.frame_id, "map");
  EXPECT_EQ(s.search_evaluations, 1234u);
  EXPECT_NEAR(s.search_fraction, 0.01234, 1e-12);
  EXPECT_NEAR(s.search_ms, 20.0, 1e-9);
  EXPECT_NEAR(s.total_ms, 50.0, 1e-9);
  EXPECT_NEAR(s.latency_ms, 120.0, 1e-9);
  EXPECT_EQ(s.dropped_scans, 2u);
  EXPECT_EQ(s.obstacle_points, 3u);
  EXPECT_NEAR(s.pose.pose.position.x, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.pose.covariance[1], 0.002);
  EXPECT_FALSE(s.certified);  // a default certificate: disabled
  EXPECT_EQ(s.certificate_failure, "disabled");
  MatchReport certified = acceptedReport();
  certified.result.certificate.certified = true;
  certified.result.certificate.failure = CertificateFailure::kNone;
  certified.result.certificate.separation_per_point = 0.3;
  certified.result.protection_xy_m = 0.35;
  certified.result.protection_heading_rad = kNaN;
  toStatusMsg(certified, "map", 0.12, 2, s);
  EXPECT_TRUE(s.certified);
  EXPECT_EQ(s.certificate_failure, "");
  EXPECT_DOUBLE_EQ(s.separation_per_point, 0.3);
  EXPECT_DOUBLE_EQ(s.protection_xy_m, 0.35);
  EXPECT_EQ(s.protection_heading_rad, 0.0);  // never NaN in a status

  MatchReport rejected = acceptedReport();
  rejected.outcome = MatchOutcome::kRejected;
  rejected.reason = "map coverage 0.1 below 0.4";
  rejected.has_result = false;
  rejected.correction_xy_m = kNaN;
  toStatusMsg(rejected, "map", kNaN, 0, s);
  EXPECT_FALSE(s.accepted);
  EXPECT_EQ(s.reason, rejected.reason);
  EXPECT_NEAR(s.pose.pose.position.x, 0.9, 1e-12);  // the prior
  EXPECT_EQ(s.pose.covariance[0], 0.0);
  EXPECT_EQ(s.correction_xy_m, 0.0);
  EXPECT_EQ(s.latency_ms, 0.0);

  MatchReport nothing;  // no prior, no result
  nothing.reason = "no prior";
  toStatusMsg(nothing, "map", 0.0, 0, s);
  EXPECT_EQ(s.prior_source, "none");
  EXPECT_DOUBLE_EQ(s.pose.pose.orientation.w, 1.0);
  EXPECT_EQ(s.window_x_m, 0.0);
  EXPECT_FALSE(s.global_search);
}

TEST(MatcherOutputs, AGlobalWindowIsReportedAsSuchWithOrWithoutAResult) {
  // The global start tells its window's answer from the others by global_search and the
  // window's centre; a search stopped at its budget (or cancelled) leaves no result.
  MatchReport r = acceptedReport();
  r.outcome = MatchOutcome::kRejected;
  r.reason = "search stopped at its budget";
  r.has_result = false;
  r.global_window = true;
  r.prior.pose.y = -4.0;
  r.window = {50.0, 50.0, M_PI};
  MatchStatus s;
  toStatusMsg(r, "map", 0.0, 0, s);
  EXPECT_TRUE(s.global_search);
  EXPECT_FALSE(s.global_certified);
  EXPECT_EQ(s.global_separation_per_point, 0.0);
  EXPECT_DOUBLE_EQ(s.window_x_m, 0.9);
  EXPECT_DOUBLE_EQ(s.window_y_m, -4.0);
  EXPECT_DOUBLE_EQ(s.window_half_x_m, 50.0);
  r.outcome = MatchOutcome::kSkipped;  // not searched (another global search runs)
  toStatusMsg(r, "map", 0.0, 0, s);
  EXPECT_FALSE(s.global_search);
  r = acceptedReport();  // a tracking window
  toStatusMsg(r, "map", 0.0, 0, s);
  EXPECT_FALSE(s.global_search);
  EXPECT_DOUBLE_EQ(s.window_x_m, 0.9);
}

TEST(MatcherOutputs, PoseOnlyWhenAcceptedAndFinite) {
  geometry_msgs::PoseWithCovarianceStamped p;
  MatchReport r = acceptedReport();
  ASSERT_TRUE(toMatchPoseMsg(r, "map", p));
  EXPECT_EQ(p.header.frame_id, "map");
  EXPECT_NEAR(p.pose.pose.orientation.z, std::sin(M_PI / 4), 1e-12);
  EXPECT_DOUBLE_EQ(p.pose.covariance[6], 0.002);  // (1, 0)
  r.pose.y = kNaN;
  EXPECT_FALSE(toMatchPoseMsg(r, "map", p));
  r = acceptedReport();
  r.covariance(2, 2) = kNaN;
  EXPECT_FALSE(toMatchPoseMsg(r, "map", p));
  r = acceptedReport();
  r.outcome = MatchOutcome::kRejected;
  EXPECT_FALSE(toMatchPoseMsg(r, "map", p));
}

TEST(MatcherOutputs, ObstacleAndClassifiedClouds) {
  const MatchReport r = acceptedReport();
  sensor_msgs::PointCloud2 c;
  ASSERT_TRUE(toObstaclesCloud(r, false, c));
  EXPECT_EQ(c.width, 2u);  // the NaN obstacle is left out
  sensor_msgs::PointCloud2ConstIterator<float> x(c, "x"), y(c, "y");
  EXPECT_FLOAT_EQ(*x, 2.0f);
  ASSERT_TRUE(toObstaclesCloud(r, true, c));  // at pose x = 1, yaw 90 deg
  sensor_msgs::PointCloud2ConstIterator<float> mx(c, "x"), my(c, "y");
  EXPECT_NEAR(*mx, 1.0f, 1e-5);
  EXPECT_NEAR(*my, 2.0f, 1e-5);

  ASSERT_TRUE(toClassifiedCloud(r, 10.0, c));
  EXPECT_EQ(c.width, 3u);
  sensor_msgs::PointCloud2ConstIterator<float> m(c, "mahalanobis");
  sensor_msgs::PointCloud2ConstIterator<uint8_t> k(c, "class");
  const float expect_m[3] = {0.5f, 4.0f, 10.0f};  // +inf clamped to 10
  const uint8_t expect_k[3] = {0, 1, 1};
  for (int i = 0; i < 3; ++i, ++m, ++k) {
    EXPECT_FLOAT_EQ(*m, expect_m[i]) << i;
    EXPECT_EQ(*k, expect_k[i]) << i;
  }

  MatchReport no_labels = r;
  no_labels.result.obstacles.label.clear();
  EXPECT_FALSE(toClassifiedCloud(no_labels, 10.0, c));
  EXPECT_FALSE(toObstaclesCloud(no_labels, true, c));
}

TEST(MatcherOutputs, TraversalImage) {
  MatchReport r = acceptedReport();
  sensor_msgs::Image img;
  EXPECT_FALSE(toTraversalImage(r, {}, img));
  r.search_window.half_x = r.search_window.half_y = 2;
  r.search_window.half_h = 0;
  r.result.search.stats.top_layer = 1;
  r.traversal = {{1, 0, 0, 0, 10}, {1, 0, 2, 0, 12}, {0, 0, 2, 1, 12}};
  ASSERT_TRUE(toTraversalImage(r, {}, img));
  EXPECT_EQ(img.encoding, sensor_msgs::image_encodings::RGB8);
  EXPECT_EQ(img.width, 5u);
  EXPECT_EQ(img.height, 2u * 5u + 2u);
  EXPECT_EQ(img.step, 15u);
  EXPECT_EQ(img.data.size(), img.step * img.height);
}

TEST(MatcherOutputs, StatusSaysWhetherTheScanWasDeskewed) {
  MatchReport r = acceptedReport();
  r.deskewed = true;
  r.time_source = "'t' uint32 relative nanoseconds";
  MatchStatus s;
  toStatusMsg(r, "map", 0.0, 0, s);
  EXPECT_TRUE(s.deskewed);
  EXPECT_EQ(s.point_times, "'t' uint32 relative nanoseconds");
  EXPECT_EQ(s.deskew_note, "");
  r.deskewed = false;
  r.deskew_note = "no twist";
  toStatusMsg(r, "map", 0.0, 0, s);
  EXPECT_FALSE(s.deskewed);
  EXPECT_EQ(s.deskew_note, "no twist");
}

/// A Hesai-like cloud (float64 `timestamp`, absolute seconds) of the corridor's walls, stamped
/// 1700000000.5, the i-th of n points at stamp + time(i).
template <typename F>
sensor_msgs::PointCloud2 hesaiCloud(F time) {
  const PointList wall = testing::corridorScan();
  sensor_msgs::PointCloud2 m;
  m.header.stamp = ros::Time(1700000000, 500000000);
  m.header.frame_id = "base_link";
  sensor_msgs::PointCloud2Modifier mod(m);
  mod.setPointCloud2Fields(
      4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32, "z", 1,
      sensor_msgs::PointField::FLOAT32, "timestamp", 1, sensor_msgs::PointField::FLOAT64);
  mod.resize(wall.size());
  sensor_msgs::PointCloud2Iterator<float> x(m, "x");
  sensor_msgs::PointCloud2Iterator<double> t(m, "timestamp");
  for (size_t i = 0; i < wall.size(); ++i, ++x, ++t) {
    x[0] = wall[i].x(), x[1] = wall[i].y(), x[2] = wall[i].z();
    *t = m.header.stamp.toSec() + time(i, wall.size());
  }
  return m;
}

MatchStatus statusOf(const sensor_msgs::PointCloud2& cloud, const BodyTwist* twist) {
  return testing::corridorMatchStatus(cloud, twist);
}

TEST(MatcherOutputs, AbsoluteDriverTimesAreDeskewedAndGarbageIsNot) {
  BodyTwist twist;
  twist.linear_mps.x() = 10.0;
  // Hesai: absolute seconds over 0.1 s after the stamp.
  auto revolution = [](size_t i, size_t n) { return 0.1 * i / n; };
  MatchStatus s = statusOf(hesaiCloud(revolution), &twist);
  EXPECT_TRUE(s.deskewed);
  EXPECT_EQ(s.point_times, "'timestamp' float64 absolute seconds");
  EXPECT_EQ(s.deskew_note, "");
  // The same cloud without a twist: not deskewed, and why.
  s = statusOf(hesaiCloud(revolution), nullptr);
  EXPECT_FALSE(s.deskewed);
  EXPECT_EQ(s.point_times, "'timestamp' float64 absolute seconds");
  EXPECT_NE(s.deskew_note.find("no twist"), std::string::npos) << s.deskew_note;
  // Times on another clock (the LIDAR's, since boot): refused, the scan matched undeskewed.
  s = statusOf(hesaiCloud([](size_t i, size_t n) { return 1234.5 - 1700000000.5 + 0.1 * i / n; }),
               &twist);
  EXPECT_FALSE(s.deskewed);
  EXPECT_EQ(s.point_times, "");
  EXPECT_NE(s.deskew_note.find("per-point 'timestamp' (float64) makes no sense"), std::string::npos)
      << s.deskew_note;
  EXPECT_GT(s.search_points, 0u);  // matched all the same
  // No time field at all.
  sensor_msgs::PointCloud2 plain = hesaiCloud(revolution);
  plain.fields.pop_back();
  s = statusOf(plain, &twist);
  EXPECT_FALSE(s.deskewed);
  EXPECT_NE(s.deskew_note.find("no per-point time field"), std::string::npos) << s.deskew_note;
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
