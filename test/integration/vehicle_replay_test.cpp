// rostest of the replay launch (test/integration/vehicle_replay.test): launch/replay.launch
// (through the fixture's fixture.launch) plays the 20 s test drive with rosbag play -(-)clock
// into launch/localization.launch, starting from an initial pose 3.2 m and 3 deg off the truth.
// The player starts paused; this node resumes it once the map server has rasterized the map
// around the initial pose, then checks at the end of the drive:
//  - the EKF pose is within 0.3 m and 1 deg of the ground truth;
//  - every scan got a matcher status (or was counted as dropped), most were matched;
//  - the EKF odometry came at its configured rate (sim time), TF map -> base_link agrees;
//  - nothing non-finite was published.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_srvs/SetBool.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <numeric>

#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

std::unique_ptr<Outputs> outputs;
std::unique_ptr<tf2_ros::Buffer> tf_buffer;
ros::WallTime node_start;

double param(const std::string& key) {
  double v = NAN;
  EXPECT_TRUE(ros::param::get("~" + key, v)) << "missing test parameter ~" << key;
  return v;
}

size_t countScans(const std::string& bag_path) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{"/velodyne_points"}));
  return view.size();
}

TEST(VehicleReplay, LocalizesTheDriveAtTheExpectedRates) {
  std::string bag_path;
  ASSERT_TRUE(ros::param::get("~bag", bag_path));
  const double end_stamp = param("end_stamp");
  const size_t scans = countScans(bag_path);
  ASSERT_GT(scans, 100u);
  double publish_rate_hz = 0.0;
  ASSERT_TRUE(ros::param::get("/localization/ekf/publish_rate_hz", publish_rate_hz));

  // 1. The map around the initial pose: every chunk within the raster radius rasterized.
  const std::string chunks = "/localization/map_server: chunks";
  ASSERT_TRUE(waitFor(
      [&] {
        const std::string held = outputs->diagnosticValue(chunks, "chunks held");
        return outputs->diagnosticValue(chunks, "chunks pending") == "0" && !held.empty() &&
               held != "0";
      },
      90.0))
      << "the map server never finished rasterizing around the initial pose";
  const double map_ready_s = (ros::WallTime::now() - node_start).toSec();
  std::printf("[vehicle_replay] map ready %.1f s after the test node started (%s chunks)\n",
              map_ready_s, outputs->diagnosticValue(chunks, "chunks held").c_str());

  // 2. Start the drive.
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", 30000));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));
  const ros::WallTime drive_start = ros::WallTime::now();

  // 3. The end of the drive (the last ground truth), then time for the last scan's status.
  ASSERT_TRUE(waitFor(
      [&] {
        return outputs->locked(
            [&] { return !outputs->truth_.empty() && outputs->truth_.last() >= end_stamp - 0.02; });
      },
      120.0))
      << "the bag never reached its end";
  ros::WallDuration(3.0).sleep();
  std::printf("[vehicle_replay] 20 s drive replayed in %.1f s wall\n",
              (ros::WallTime::now() - drive_start).toSec());

  // A copy of what was recorded (the checks below may ASSERT).
  std::vector<MatchStatus> st;
  std::vector<geometry_msgs::PoseWithCovarianceStamped> poses;
  std::vector<nav_msgs::Odometry> od;
  Truth truth;
  outputs->locked([&] {
    st = outputs->statuses_;
    poses = outputs->poses_;
    od = outputs->odometry_;
    truth = outputs->truth_;
    return 0;
  });
  {
    // Every scan has a status, or was dropped (the matcher's queue drains within the 3 s above).
    uint64_t dropped = 0, accepted = 0;
    for (const MatchStatus& s : st) {
      dropped += s.dropped_scans;
      accepted += s.accepted ? 1 : 0;
    }
    EXPECT_EQ(st.size() + dropped, scans) << st.size() << " statuses, " << dropped << " dropped";
    for (size_t i = 1; i < st.size(); ++i) {
      EXPECT_GT(st[i].header.stamp, st[i - 1].header.stamp) << "status " << i;
    }
    EXPECT_GE(st.size(), scans / 2) << "more than half of the scans were dropped";
    EXPECT_GE(accepted, 8 * st.size() / 10) << "fewer than 80% of the processed scans matched";
    std::vector<double> latency;
    for (const MatchStatus& s : st) {
      if (s.accepted) latency.push_back(s.latency_ms);
    }
    std::sort(latency.begin(), latency.end());
    std::printf(
        "[vehicle_replay] %zu scans: %zu statuses, %lu dropped, %lu accepted; latency median "
        "%.0f ms, max %.0f ms\n",
        scans, st.size(), static_cast<unsigned long>(dropped), static_cast<unsigned long>(accepted),
        latency.empty() ? 0.0 : latency[latency.size() / 2],
        latency.empty() ? 0.0 : latency.back());

    // The first match searched the window of the configured initial pose and found the truth.
    auto first =
        std::find_if(st.begin(), st.end(), [](const MatchStatus& s) { return s.accepted; });
    ASSERT_NE(first, st.end());
    EXPECT_EQ(first->prior_source, "configured");
    EXPECT_GE(first->window_half_x_m, 3.2) << "the initial pose is 3.2 m off: a wider window";
    EXPECT_GE(first->correction_xy_m, 2.0) << "the first match corrected the initial pose";
    const PoseError first_error =
        poseError(truth, first->header.stamp.toSec(), toPose(first->pose.pose));
    EXPECT_LE(first_error.xy_m, kTolXyM);

    // Accepted matches against the truth.
    std::vector<double> match_xy;
    for (const auto& p : poses) {
      EXPECT_EQ(p.header.frame_id, "map");
      const PoseError e = poseError(truth, p.header.stamp.toSec(), toPose(p.pose.pose));
      if (e.valid()) match_xy.push_back(e.xy_m);
    }
    ASSERT_FALSE(match_xy.empty());
    std::sort(match_xy.begin(), match_xy.end());
    EXPECT_LE(match_xy[match_xy.size() * 95 / 100], kTolXyM) << "95th percentile of match errors";

    // EKF odometry: frames, rate in sim time, increasing stamps, accuracy.
    ASSERT_GT(od.size(), 100u);
    EXPECT_EQ(od.back().header.frame_id, "map");
    EXPECT_EQ(od.back().child_frame_id, "base_link");
    for (size_t i = 1; i < od.size(); ++i) {
      ASSERT_GT(od[i].header.stamp, od[i - 1].header.stamp) << "odometry " << i;
    }
    const double span = (od.back().header.stamp - od.front().header.stamp).toSec();
    const double rate = (od.size() - 1) / span;
    EXPECT_GE(rate, 0.7 * publish_rate_hz) << "EKF odometry rate (sim time)";
    EXPECT_LE(rate, 1.05 * publish_rate_hz) << "EKF odometry rate (sim time)";
    double max_xy = 0.0, max_yaw = 0.0;
    const double settled = first->header.stamp.toSec() + 2.0;
    for (const auto& o : od) {
      if (o.header.stamp.toSec() < settled) continue;
      const PoseError e = poseError(truth, o.header.stamp.toSec(), toPose(o.pose.pose));
      if (!e.valid()) continue;
      max_xy = std::max(max_xy, e.xy_m);
      max_yaw = std::max(max_yaw, e.yaw_rad);
    }
    // The last estimate the truth covers (the clock may end a few ms after the last truth).
    PoseError final_error;
    size_t last = od.size();
    while (last > 0 && !final_error.valid()) {
      --last;
      final_error = poseError(truth, od[last].header.stamp.toSec(), toPose(od[last].pose.pose));
    }
    std::printf(
        "[vehicle_replay] EKF odometry %zu at %.1f Hz (sim); error from 2 s after the first "
        "match: max %.3f m, %.3f deg; final %.3f m, %.3f deg\n",
        od.size(), rate, max_xy, max_yaw * 180.0 / M_PI, final_error.xy_m,
        final_error.yaw_rad * 180.0 / M_PI);
    ASSERT_TRUE(final_error.valid());
    EXPECT_LE(final_error.xy_m, kTolXyM);
    EXPECT_LE(final_error.yaw_rad, kTolYawRad);
    EXPECT_LE(max_xy, 2.0 * kTolXyM) << "the EKF strayed during the drive";
    EXPECT_LE(max_yaw, 2.0 * kTolYawRad) << "the EKF strayed during the drive";

    // TF map -> base_link (the EKF's map -> odom with the INS odom -> base_link) agrees.
    try {
      const auto t =
          tf_buffer->lookupTransform("map", "base_link", od[last].header.stamp, ros::Duration(0.0));
      const Pose6 via_tf = fromIsometry(fromMsg(t.transform));
      const Pose6 ekf = toPose(od[last].pose.pose);
      EXPECT_LE(std::hypot(via_tf.x - ekf.x, via_tf.y - ekf.y), 0.05);
      EXPECT_LE(std::abs(angleDiff(via_tf.yaw, ekf.yaw)), 0.002);
    } catch (const tf2::TransformException& e) {
      ADD_FAILURE() << "no TF map -> base_link at the last estimate: " << e.what();
    }
  }
  outputs->locked([] {
    EXPECT_FALSE(outputs->non_finite_) << outputs->non_finite_what_;
    return 0;
  });
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_replay_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  using namespace gmm_localization::node;  // NOLINT: test code
  node_start = ros::WallTime::now();
  outputs = std::make_unique<vehicle_test::Outputs>(nh, /*subscribe_truth=*/true);
  tf_buffer = std::make_unique<tf2_ros::Buffer>(ros::Duration(60.0));
  tf2_ros::TransformListener listener(*tf_buffer);
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  outputs.reset();
  return result;
}
