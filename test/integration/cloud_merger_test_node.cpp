// rostest node for the cloud_merger nodelet (test/integration/cloud_merger.test). Publishes
// static TFs base_link -> velodyne_0..3 and four synthetic clouds per revolution, and checks:
//  - the merged cloud is in base_link, stamped with the earliest input stamp, each point where
//    the extrinsic puts it, times re-based, NaN points dropped, ring and intensity kept;
//  - malformed clouds (a missing field, sizes that disagree) are dropped with a diagnostic
//    naming the input and the reason, and merging goes on;
//  - a silent sensor: scans still come (after max_wait_s) and a diagnostic names it;
//  - time going backwards (a looping bag) resets the merger, which recovers.
#include <cmath>
#include <mutex>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "gmm_localization/ros/cloud_conversion.h"
#include "gmm_localization/ros/pose_conversion.h"
#include "rostest_main.h"

namespace gmm_localization {
namespace node {
namespace {

constexpr int kSensors = 4;
const double kPhaseS[kSensors] = {0.0, 0.023, 0.051, 0.074};

/// Roof extrinsics: corners of a 2 x 1 m rectangle 1.9 m up, yawed 45 + 90 i degrees.
Eigen::Isometry3d extrinsic(int i) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(i < 2 ? 1.0 : -1.0, (i % 2 == 0) ? 0.5 : -0.5, 1.9);
  T.linear() =
      Eigen::AngleAxisd((45.0 + 90.0 * i) * M_PI / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  return T;
}

/// Sensor i's cloud: 10 points at (5 + j, i, -1) in its frame, time 0.001 j, ring j, intensity
/// 10 i + j; point 3 is NaN.
sensor_msgs::PointCloud2 sensorCloud(int i, const ros::Time& stamp) {
  CloudData c;
  for (int j = 0; j < 10; ++j) {
    c.points.emplace_back(5.f + j, static_cast<float>(i), -1.f);
    c.time_s.push_back(0.001f * j);
    c.ring.push_back(static_cast<uint16_t>(j));
    c.intensity.push_back(10.f * i + j);
  }
  c.points[3].x() = NAN;
  sensor_msgs::PointCloud2 msg;
  toMsg(c, msg);
  msg.header.stamp = stamp;
  msg.header.frame_id = "velodyne_" + std::to_string(i);
  return msg;
}

class CloudMergerRostest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < kSensors; ++i) {
      pubs_.push_back(nh_.advertise<sensor_msgs::PointCloud2>(
          "/velodyne_" + std::to_string(i) + "/velodyne_points", 10));
      geometry_msgs::TransformStamped t;
      t.header.stamp = ros::Time::now();
      t.header.frame_id = "base_link";
      t.child_frame_id = "velodyne_" + std::to_string(i);
      toMsg(extrinsic(i), t.transform);
      tfs_.push_back(t);
    }
    tf_.sendTransform(tfs_);
    sub_ = nh_.subscribe("/velodyne_points", 100, &CloudMergerRostest::onMerged, this);
    diag_sub_ = nh_.subscribe("/diagnostics", 100, &CloudMergerRostest::onDiagnostics, this);
    // Wait for the merger's subscriptions and ours.
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(20.0);
    auto connected = [&]() {
      for (auto& p : pubs_) {
        if (p.getNumSubscribers() == 0) return false;
      }
      return sub_.getNumPublishers() > 0;
    };
    while (!connected() && ros::WallTime::now() < end) ros::WallDuration(0.05).sleep();
    ASSERT_TRUE(connected()) << "cloud_merger did not connect";
  }
  // Before the members the callbacks write: shutdown() waits for a callback in progress.
  void TearDown() override {
    sub_.shutdown();
    diag_sub_.shutdown();
  }

  void onMerged(const sensor_msgs::PointCloud2::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    merged_.push_back(m);
  }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : m->status) {
      if (s.hardware_id.find("cloud_merger") != std::string::npos) diag_.push_back(s);
    }
  }

  /// Publishes the sensors' clouds of one revolution starting at t (in phase order).
  void publishRevolution(const ros::Time& t, const std::vector<int>& sensors = {0, 1, 2, 3}) {
    for (int i : sensors) {
      pubs_[i].publish(sensorCloud(i, t + ros::Duration(kPhaseS[i])));
      ros::WallDuration(0.002).sleep();
    }
  }

  /// Waits for a merged cloud stamped `stamp`; nullptr after timeout_s.
  sensor_msgs::PointCloud2::ConstPtr waitMerged(const ros::Time& stamp, double timeout_s = 5.0) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::WallTime::now() < end) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& m : merged_) {
          if (m->header.stamp == stamp) return m;
        }
      }
      ros::WallDuration(0.01).sleep();
    }
    return nullptr;
  }

  /// Waits for a cloud_merger diagnostic whose name contains `name` with level >= WARN and a
  /// message containing `text`.
  bool waitDiagnostic(const std::string& name, const std::string& text, double timeout_s = 5.0) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::WallTime::now() < end) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& s : diag_) {
          if (s.name.find(name) != std::string::npos && s.level >= s.WARN &&
              s.message.find(text) != std::string::npos) {
            return true;
          }
        }
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }

  /// Publishes revolutions until one is merged with all four sensors (the merger's TF listener
  /// needs a moment for /tf_static); returns the merged cloud of the last one.
  sensor_msgs::PointCloud2::ConstPtr warmUp(ros::Time& t) {
    for (int attempt = 0; attempt < 40; ++attempt) {
      t += ros::Duration(0.1);
      publishRevolution(t);
      auto m = waitMerged(t, 1.0);
      if (m && m->width == kSensors * 9) return m;
    }
    return nullptr;
  }

  ros::NodeHandle nh_;
  std::vector<ros::Publisher> pubs_;
  tf2_ros::StaticTransformBroadcaster tf_;
  std::vector<geometry_msgs::TransformStamped> tfs_;
  ros::Subscriber sub_, diag_sub_;
  std::mutex mutex_;
  std::vector<sensor_msgs::PointCloud2::ConstPtr> merged_;
  std::vector<diagnostic_msgs::DiagnosticStatus> diag_;
};

TEST_F(CloudMergerRostest, MergesIntoBaseLinkAndSurvivesBadInput) {
  ros::Time t = ros::Time::now();
  auto m = warmUp(t);
  ASSERT_TRUE(m) << "no complete merged scan";

  // 1. Geometry, stamp, fields, re-based times.
  EXPECT_EQ(m->header.frame_id, "base_link");
  EXPECT_EQ(m->header.stamp, t) << "stamped with the earliest input";
  EXPECT_TRUE(m->is_dense);
  auto cloud = fromMsg(*m);
  ASSERT_TRUE(cloud.ok()) << cloud.error();
  ASSERT_EQ(cloud->points.size(), static_cast<size_t>(kSensors * 9)) << "NaN points dropped";
  ASSERT_EQ(cloud->time_s.size(), cloud->points.size());
  ASSERT_EQ(cloud->ring.size(), cloud->points.size());
  ASSERT_EQ(cloud->intensity.size(), cloud->points.size());
  size_t k = 0;
  for (int i = 0; i < kSensors; ++i) {
    for (int j = 0; j < 10; ++j) {
      if (j == 3) continue;
      const Eigen::Vector3d want = extrinsic(i) * Eigen::Vector3d(5.0 + j, i, -1.0);
      EXPECT_NEAR((cloud->points[k].cast<double>() - want).norm(), 0.0, 1e-5)
          << "sensor " << i << " point " << j;
      EXPECT_NEAR(cloud->time_s[k], kPhaseS[i] + 0.001 * j, 1e-6);
      EXPECT_EQ(cloud->ring[k], j);
      EXPECT_EQ(cloud->intensity[k], 10.f * i + j);
      ++k;
    }
  }

  // 2. Malformed clouds: a missing field and sizes that disagree. Dropped, named, survived.
  t += ros::Duration(0.1);
  auto no_z = sensorCloud(1, t + ros::Duration(kPhaseS[1]));
  no_z.fields.erase(no_z.fields.begin() + 2);
  auto short_data = sensorCloud(2, t + ros::Duration(kPhaseS[2]));
  short_data.data.resize(short_data.data.size() - 5);
  pubs_[0].publish(sensorCloud(0, t));
  pubs_[1].publish(no_z);
  pubs_[2].publish(short_data);
  pubs_[3].publish(sensorCloud(3, t + ros::Duration(kPhaseS[3])));
  auto partial = waitMerged(t);
  ASSERT_TRUE(partial) << "the merger must publish the sensors it has";
  EXPECT_EQ(partial->width, 2u * 9);
  EXPECT_TRUE(waitDiagnostic("velodyne_1/velodyne_points", "x, y or z"));
  EXPECT_TRUE(waitDiagnostic("velodyne_2/velodyne_points", "data size"));
  EXPECT_TRUE(waitDiagnostic("output", "velodyne_1"));
  t += ros::Duration(0.1);
  publishRevolution(t);
  auto after = waitMerged(t);
  ASSERT_TRUE(after);
  EXPECT_EQ(after->width, static_cast<uint32_t>(kSensors * 9)) << "merging goes on";

  // 3. A silent sensor: scans keep coming (max_wait_s), the diagnostic names it.
  for (int rev = 0; rev < 3; ++rev) {
    t += ros::Duration(0.1);
    publishRevolution(t, {0, 1, 3});
    auto three = waitMerged(t);
    ASSERT_TRUE(three);
    EXPECT_EQ(three->width, 3u * 9);
  }
  EXPECT_TRUE(waitDiagnostic("output", "velodyne_2"));

  // 4. Time going backwards by 100 s (a looping bag): reset, then merging from the new time.
  t -= ros::Duration(100.0);
  publishRevolution(t);
  auto looped = waitMerged(t);
  ASSERT_TRUE(looped) << "no scan after time went backwards";
  EXPECT_EQ(looped->width, static_cast<uint32_t>(kSensors * 9));
  t += ros::Duration(0.1);
  publishRevolution(t);
  EXPECT_TRUE(waitMerged(t));
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  return gmm_localization::node::runRostestMain(argc, argv, "cloud_merger_rostest");
}
