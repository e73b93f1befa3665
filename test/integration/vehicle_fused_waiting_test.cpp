// rostest of the matcher's fused method without a usable reflectivity layer
// (test/integration/vehicle_fused_waiting.test: the height map server and the matcher, no
// reflectivity map server). With the height map held and a pose on /initialpose:
//  - each scan is answered skipped, the reason naming the missing layer and its topic; no pose
//    is published; the diagnostics count the scans and WARN;
//  - once an index of another resolution arrives on reflectivity/map_index, an ERROR line and
//    diagnostic name both map directories and what differs, and the scans are answered skipped
//    with that reason.
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <memory>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/ros/cloud_conversion.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

std::unique_ptr<Outputs> outputs;
const std::string kMatching = "/localization/matcher: scan matching";

/// A scan of a flat ring of ground returns with intensities, stamped now.
sensor_msgs::PointCloud2 groundScan() {
  CloudData cloud;
  for (int i = 0; i < 2000; ++i) {
    const double a = 2.0 * M_PI * i / 2000.0, r = 5.0 + (i % 20);
    cloud.points.emplace_back(static_cast<float>(r * std::cos(a)),
                              static_cast<float>(r * std::sin(a)), 0.0f);
    cloud.intensity.push_back(static_cast<float>(20 + i % 50));
  }
  sensor_msgs::PointCloud2 msg;
  toMsg(cloud, msg);
  msg.header.frame_id = "base_link";
  msg.header.stamp = ros::Time::now();
  return msg;
}

/// Publishes scans until a status containing `text` arrives; returns that status's reason.
std::string answerContaining(ros::Publisher& scans, const std::string& text) {
  std::string reason;
  waitFor(
      [&] {
        scans.publish(groundScan());
        ros::WallDuration(0.3).sleep();
        return outputs->locked([&] {
          for (const MatchStatus& s : outputs->statuses_) {
            if (s.reason.find(text) != std::string::npos) {
              reason = s.reason;
              return true;
            }
          }
          return false;
        });
      },
      20.0);
  return reason;
}

TEST(VehicleFusedWaiting, ScansAnsweredUntilTheLayerIsUsable) {
  ros::NodeHandle nh;
  double x = NAN, y = NAN, z = NAN, yaw = NAN;
  ASSERT_TRUE(ros::param::get("~truth_start/x", x) && ros::param::get("~truth_start/y", y) &&
              ros::param::get("~truth_start/z", z) && ros::param::get("~truth_start/yaw", yaw));
  ros::Publisher pose_pub =
      nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1, true);
  ros::Publisher scan_pub = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_points", 5);
  ros::Publisher index_pub =
      nh.advertise<MapIndex>("/localization/reflectivity/map_index", 1, true);
  MapIndex::ConstPtr height_index;
  ros::Subscriber index_sub = nh.subscribe<MapIndex>(
      "/localization/map_index", 1, [&](const MapIndex::ConstPtr& m) { height_index = m; });

  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header.frame_id = "map";
  pose.header.stamp = ros::Time::now();
  pose.pose.pose.position.x = x;
  pose.pose.pose.position.y = y;
  pose.pose.pose.position.z = z;
  pose.pose.pose.orientation.z = std::sin(yaw / 2);
  pose.pose.pose.orientation.w = std::cos(yaw / 2);
  pose.pose.covariance[0] = pose.pose.covariance[7] = 0.25;
  pose.pose.covariance[35] = 0.01;
  pose_pub.publish(pose);

  // The height map around the pose reaches the matcher.
  ASSERT_TRUE(waitFor(
      [&] {
        const std::string held = outputs->diagnosticValue(kMatching, "chunks held");
        return !held.empty() && held != "0";
      },
      30.0))
      << "the matcher never held the height map";

  // 1. No reflectivity layer: answered, with the reason and the topic.
  const std::string missing = answerContaining(scan_pub, "no reflectivity layer yet");
  ASSERT_FALSE(missing.empty()) << "no scan answered with the missing layer";
  EXPECT_NE(missing.find("/localization/reflectivity/map_index"), std::string::npos) << missing;
  outputs->locked([] {
    for (const MatchStatus& s : outputs->statuses_) {
      EXPECT_FALSE(s.accepted) << "accepted without a reflectivity layer";
    }
    EXPECT_TRUE(outputs->poses_.empty()) << "a pose published without a reflectivity layer";
    return 0;
  });
  ASSERT_TRUE(waitFor(
      [&] {
        const std::string n = outputs->diagnosticValue(
            kMatching, "scans skipped without a usable reflectivity layer");
        return !n.empty() && n != "0";
      },
      5.0));
  const double since = ros::WallTime::now().toSec();
  ASSERT_TRUE(waitFor(
      [&] {
        return outputs->sawDiagnostic(
            kMatching,
            [](const diagnostic_msgs::DiagnosticStatus& s) {
              return s.level == diagnostic_msgs::DiagnosticStatus::WARN &&
                     s.message.find("no reflectivity layer yet") != std::string::npos;
            },
            since);
      },
      5.0));

  // 2. A reflectivity index that cannot be searched with the height map (another resolution).
  ASSERT_TRUE(waitFor([&] { return height_index != nullptr; }, 10.0));
  MapIndex other = *height_index;
  other.resolution_m = 2.0 * height_index->resolution_m;
  other.map_directory = "/maps/coarse_reflectivity";
  other.chunk_x.clear();
  other.chunk_y.clear();
  other.header.stamp = ros::Time::now();
  index_pub.publish(other);
  const std::string mismatch = answerContaining(scan_pub, "cannot be searched together");
  ASSERT_FALSE(mismatch.empty()) << "no scan answered with the layers' mismatch";
  EXPECT_NE(mismatch.find(height_index->map_directory), std::string::npos) << mismatch;
  EXPECT_NE(mismatch.find("/maps/coarse_reflectivity"), std::string::npos) << mismatch;
  EXPECT_NE(mismatch.find("resolution"), std::string::npos) << mismatch;
  EXPECT_TRUE(waitFor(
      [&] {
        return outputs->sawDiagnostic(
            kMatching,
            [](const diagnostic_msgs::DiagnosticStatus& s) {
              return s.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
                     s.message.find("cannot be searched together") != std::string::npos;
            },
            since);
      },
      5.0));
  EXPECT_TRUE(outputs->sawLog(rosgraph_msgs::Log::ERROR, "/maps/coarse_reflectivity", since));
  outputs->locked([] {
    EXPECT_FALSE(outputs->non_finite_) << outputs->non_finite_what_;
    EXPECT_TRUE(outputs->poses_.empty()) << "a pose published without a usable layer";
    return 0;
  });
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_fused_waiting_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  gmm_localization::node::outputs = std::make_unique<gmm_localization::node::vehicle_test::Outputs>(
      nh, /*subscribe_truth=*/false);
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  gmm_localization::node::outputs.reset();
  return result;
}
