// rostest of launch/localization.launch with another filter instead of our EKF
// (vehicle_external_filter.test: ekf:=false prior_topic:=/odometry/filtered). robot_localization
// is not packaged in Debian bookworm, so this node stands in for its ekf_localization_node: it
// turns each /localization/pose into nav_msgs/Odometry on /odometry/filtered (frame map, child
// base_link), the topic the shipped config/robot_localization.yaml makes it publish. It plays
// the fixture's 20 s drive on sim time (vehicle_test_player.h) from an /initialpose 2 m off.
// Checked: the sample configuration names the matcher's pose and our frames; no EKF nodelet is
// loaded and nobody publishes /localization/odometry; the manager subscribes /odometry/filtered
// and publishes /localization/pose; matches take their prior from /odometry/filtered ("ekf")
// and the last match ends within 0.3 m / 1 deg of the truth.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include <nodelet/NodeletList.h>
#include <yaml-cpp/yaml.h>

#include "vehicle_test_player.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

const char* kManager = "/localization/localization_manager";
constexpr double kTolXyM = 0.3, kTolYawRad = 1.0 * M_PI / 180.0;

std::unique_ptr<Outputs> outputs;
std::unique_ptr<FaultyPlayer> player;
ros::Publisher initialpose_pub, filtered_pub;
std::string config_path;

double wallNow() { return ros::WallTime::now().toSec(); }

/// The stand-in filter: the match as the filtered estimate.
void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
  nav_msgs::Odometry o;
  o.header = m->header;
  o.child_frame_id = "base_link";
  o.pose = m->pose;
  filtered_pub.publish(o);
}

TEST(VehicleExternalFilter, TheSampleConfigurationConsumesTheMatcherPose) {
  const YAML::Node c = YAML::LoadFile(config_path);
  EXPECT_EQ(c["pose0"].as<std::string>(), "/localization/pose");
  EXPECT_EQ(c["world_frame"].as<std::string>(), "map");
  EXPECT_EQ(c["map_frame"].as<std::string>(), "map");
  EXPECT_EQ(c["odom_frame"].as<std::string>(), "odom");
  EXPECT_EQ(c["base_link_frame"].as<std::string>(), "base_link");
  EXPECT_EQ(c["odom0"].as<std::string>(), "/ins/odom");
  EXPECT_EQ(c["imu0"].as<std::string>(), "/imu/data");
  for (const char* key : {"pose0_config", "odom0_config", "imu0_config"}) {
    ASSERT_TRUE(c[key].IsSequence()) << key;
    EXPECT_EQ(c[key].size(), 15u) << key;
  }
  // x, y, z, roll, pitch, yaw from the matcher.
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(c["pose0_config"][i].as<bool>()) << i;
}

TEST(VehicleExternalFilter, NoEkfAndThePriorTopicIsWired) {
  ASSERT_TRUE(ros::service::waitForService(std::string(kManager) + "/list", 30000));
  nodelet::NodeletList list;
  std::set<std::string> loaded;
  ASSERT_TRUE(waitFor(
      [&] {
        if (!ros::service::call(std::string(kManager) + "/list", list)) return false;
        loaded =
            std::set<std::string>(list.response.nodelets.begin(), list.response.nodelets.end());
        return loaded.count("/localization/matcher") && loaded.count("/localization/map_server");
      },
      30.0));
  EXPECT_EQ(loaded.count("/localization/ekf"), 0u) << "ekf:=false still loads the EKF";
  Graph g;
  ASSERT_TRUE(waitFor(
      [&] {
        g = Graph();
        return readGraph(&g) && g.subscribers["/odometry/filtered"].count(kManager) == 1;
      },
      30.0))
      << "the matcher does not subscribe /odometry/filtered";
  EXPECT_EQ(g.publishers["/localization/pose"].count(kManager), 1u);
  EXPECT_EQ(g.publishers["/localization/odometry"].size(), 0u)
      << "somebody publishes our EKF's odometry";
  EXPECT_EQ(g.subscribers["/localization/odometry"].count(kManager), 0u)
      << "the matcher still reads the EKF's topic";
}

TEST(VehicleExternalFilter, LocalizesWithTheOtherFiltersPrior) {
  ASSERT_TRUE(waitFor([] { return initialpose_pub.getNumSubscribers() > 0; }, 30.0));
  player->publishStartClock();
  ros::WallDuration(0.5).sleep();
  const double since = wallNow();
  auto t = player->truth().at(player->start().toSec());
  ASSERT_TRUE(t.has_value());
  geometry_msgs::PoseWithCovarianceStamped start;
  start.header.frame_id = "map";
  start.header.stamp = player->start();
  Pose6 p = *t;
  p.x += 2.0;
  p.y -= 1.5;
  p.yaw += 2.0 * M_PI / 180.0;
  p.z = p.roll = p.pitch = 0.0;
  start.pose.pose = toMsg(p);
  start.pose.covariance[0] = start.pose.covariance[7] = 0.25;
  start.pose.covariance[35] = 0.0076;
  initialpose_pub.publish(start);
  ASSERT_TRUE(outputs->mapReadySince(since, 60.0)) << "no map around /initialpose";
  player->play();
  ASSERT_TRUE(waitFor([] { return player->finished(); }, 150.0));
  ros::WallDuration(2.0).sleep();
  size_t accepted = 0, from_filter = 0;
  outputs->locked([&] {
    for (const MatchStatus& s : outputs->statuses_) {
      accepted += s.accepted;
      from_filter += s.accepted && s.prior_source == "ekf";
    }
    return 0;
  });
  EXPECT_GE(accepted, 100u);
  EXPECT_GE(from_filter, accepted / 2) << "matches did not take the other filter's prior";
  const PoseError e = outputs->locked([&] {
    PoseError last;
    for (auto it = outputs->poses_.rbegin(); it != outputs->poses_.rend() && !last.valid(); ++it) {
      last = poseError(player->truth(), it->header.stamp.toSec(), toPose(it->pose.pose));
    }
    return last;
  });
  ASSERT_TRUE(e.valid()) << "no match pose within the ground truth's time span";
  std::printf("[vehicle_external_filter] final match error %.3f m, %.3f deg\n", e.xy_m,
              e.yaw_rad * 180.0 / M_PI);
  EXPECT_LE(e.xy_m, kTolXyM);
  EXPECT_LE(e.yaw_rad, kTolYawRad);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_external_filter_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  using namespace gmm_localization::node;  // NOLINT: test code
  std::string bag;
  if (!ros::param::get("~bag", bag) ||
      !ros::param::get("~robot_localization_config", config_path)) {
    std::fprintf(stderr, "missing ~bag (fixture.yaml) or ~robot_localization_config\n");
    return 1;
  }
  outputs = std::make_unique<vehicle_test::Outputs>(nh, /*subscribe_truth=*/false);
  player = std::make_unique<vehicle_test::FaultyPlayer>(nh, bag, vehicle_test::Faults{});
  initialpose_pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1);
  filtered_pub = nh.advertise<nav_msgs::Odometry>("/odometry/filtered", 20);
  ros::Subscriber pose_sub = nh.subscribe("/localization/pose", 20, onPose);
  const int result = RUN_ALL_TESTS();
  player.reset();
  spinner.stop();
  outputs.reset();
  return result;
}
