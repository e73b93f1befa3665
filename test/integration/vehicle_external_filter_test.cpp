// rostest of launch/localization.launch wired for another filter, in two modes (~mode):
//  - no_ekf     (vehicle_external_filter.test: ekf:=false prior_topic:=/odometry/filtered), as with
//               robot_localization. robot_localization is not packaged in Debian bookworm, so this
//               node stands in for its ekf_localization_node with config/robot_localization.yaml:
//               each /localization/pose becomes nav_msgs/Odometry on /odometry/filtered (frame
//               map, child base_link) and TF map -> odom (the match composed with the INS's
//               odom -> base_link at its stamp).
//  - ekf_no_tf  (vehicle_ekf_no_tf.test: ekf_publish_tf:=false): our EKF runs but another node
//               broadcasts map -> odom; this node does, from the EKF's /localization/odometry.
// It plays the first kPlayS seconds of the fixture's drive on sim time (vehicle_test_player.h)
// from an /initialpose 2.5 m / 2 deg off. Checked: the sample configuration parses and names the
// matcher's pose, the INS and the IMU in our frames; the nodelets loaded (EKF or not) and the
// topics the manager publishes and subscribes (master graph); nobody but this node broadcasts
// map -> odom; matches take their prior from the filter ("ekf" prior source); the map server
// follows TF; the last match (and in ekf_no_tf the last EKF estimate) ends within 0.3 m / 1 deg
// of the truth; nothing non-finite.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include <nodelet/NodeletList.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include "vehicle_test_player.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

const char* kManager = "/localization/localization_manager";
const char* kPositionDiag = "/localization/map_server: vehicle position";
constexpr double kPlayS = 14.0;  ///< bag seconds played (of 20): keeps the test near 25 s

std::string mode;  ///< "no_ekf" or "ekf_no_tf"
bool noEkf() { return mode == "no_ekf"; }

std::unique_ptr<Outputs> outputs;
std::unique_ptr<FaultyPlayer> player;
std::unique_ptr<tf2_ros::Buffer> tf_buffer;
std::unique_ptr<tf2_ros::TransformListener> tf_listener;
std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster;
ros::Publisher initialpose_pub, filtered_pub;
std::string config_path;

std::mutex relay_mutex;
std::set<std::string> map_odom_publishers;  ///< callers seen broadcasting map -> odom
size_t map_odom_sent = 0;                   ///< map -> odom transforms this node sent
ros::Time last_sent;

double wallNow() { return ros::WallTime::now().toSec(); }

std::string bare(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

/// Broadcasts map -> odom so that map -> base_link is `map_T_base` at `stamp` (the INS's
/// odom -> base_link from TF); false when TF does not have it yet.
bool sendMapToOdom(const ros::Time& stamp, const geometry_msgs::Pose& map_T_base) {
  geometry_msgs::TransformStamped odom_T_base;
  try {
    odom_T_base = tf_buffer->lookupTransform("odom", "base_link", stamp);
  } catch (const tf2::TransformException&) {
    return false;
  }
  const Eigen::Isometry3d map_T_odom =
      fromMsg(map_T_base) * fromMsg(odom_T_base.transform).inverse();
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = "map";
  t.child_frame_id = "odom";
  toMsg(map_T_odom, t.transform);
  tf_broadcaster->sendTransform(t);
  std::lock_guard<std::mutex> lock(relay_mutex);
  ++map_odom_sent;
  last_sent = stamp;
  return true;
}

/// no_ekf: the stand-in filter, the match as the filtered estimate (+ TF map -> odom).
void onPose(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
  nav_msgs::Odometry o;
  o.header = m->header;
  o.child_frame_id = "base_link";
  o.pose = m->pose;
  filtered_pub.publish(o);
  sendMapToOdom(m->header.stamp, m->pose.pose);
}

/// ekf_no_tf: map -> odom from our EKF's odometry, at most every 50 ms (bag time).
void onEkfOdometry(const nav_msgs::Odometry::ConstPtr& m) {
  {
    std::lock_guard<std::mutex> lock(relay_mutex);
    if (!last_sent.isZero() && m->header.stamp < last_sent + ros::Duration(0.05)) return;
  }
  sendMapToOdom(m->header.stamp, m->pose.pose);
}

/// Who broadcasts map -> odom (the publisher's node name from the connection header).
void onTf(const ros::MessageEvent<const tf2_msgs::TFMessage>& event) {
  for (const auto& t : event.getConstMessage()->transforms) {
    if (bare(t.header.frame_id) == "map" && bare(t.child_frame_id) == "odom") {
      std::lock_guard<std::mutex> lock(relay_mutex);
      map_odom_publishers.insert(event.getPublisherName());
    }
  }
}

TEST(VehicleExternalFilter, TheSampleConfigurationConsumesTheMatcherPose) {
  if (!noEkf()) GTEST_SKIP() << "no_ekf only";
  YAML::Node c;
  ASSERT_NO_THROW(c = YAML::LoadFile(config_path)) << config_path;
  ASSERT_TRUE(c.IsMap());
  EXPECT_EQ(c["pose0"].as<std::string>(), "/localization/pose");
  EXPECT_EQ(c["world_frame"].as<std::string>(), "map");
  EXPECT_EQ(c["map_frame"].as<std::string>(), "map");
  EXPECT_EQ(c["odom_frame"].as<std::string>(), "odom");
  EXPECT_EQ(c["base_link_frame"].as<std::string>(), "base_link");
  EXPECT_FALSE(c["two_d_mode"].as<bool>());
  EXPECT_TRUE(c["publish_tf"].as<bool>());
  EXPECT_EQ(c["odom0"].as<std::string>(), "/ins/odom");
  EXPECT_EQ(c["imu0"].as<std::string>(), "/imu/data");
  for (const char* key : {"pose0_config", "odom0_config", "imu0_config"}) {
    ASSERT_TRUE(c[key].IsSequence()) << key;
    ASSERT_EQ(c[key].size(), 15u) << key;
  }
  // x, y, z, roll, pitch, yaw from the matcher and nothing else; vx, vy, vz from the INS.
  for (int i = 0; i < 15; ++i) {
    EXPECT_EQ(c["pose0_config"][i].as<bool>(), i < 6) << "pose0_config " << i;
    EXPECT_EQ(c["odom0_config"][i].as<bool>(), i >= 6 && i < 9) << "odom0_config " << i;
  }
  // The matches arrive after their scan: the filter must fuse them at their stamp.
  EXPECT_TRUE(c["smooth_lagged_data"].as<bool>());
  EXPECT_GE(c["history_length"].as<double>(), 0.5);
}

TEST(VehicleExternalFilter, TheNodeletsAndTopicsAreWired) {
  ASSERT_TRUE(ros::service::waitForService(std::string(kManager) + "/list", 30000));
  nodelet::NodeletList list;
  std::set<std::string> loaded;
  ASSERT_TRUE(waitFor(
      [&] {
        if (!ros::service::call(std::string(kManager) + "/list", list)) return false;
        loaded =
            std::set<std::string>(list.response.nodelets.begin(), list.response.nodelets.end());
        return loaded.count("/localization/matcher") && loaded.count("/localization/map_server") &&
               (noEkf() || loaded.count("/localization/ekf")) &&
               loaded.count("/localization/global_start");
      },
      30.0))
      << "nodelets loaded: " << loaded.size()
      << " (the global start too: localization.launch loads it by default, with no pose "
         "configured)";
  Graph g;
  const std::string prior = noEkf() ? "/odometry/filtered" : "/localization/odometry";
  ASSERT_TRUE(waitFor(
      [&] {
        g = Graph();
        return readGraph(&g) && g.subscribers[prior].count(kManager) == 1 &&
               g.publishers["/localization/pose"].count(kManager) == 1;
      },
      30.0))
      << "the matcher does not subscribe " << prior << " or does not publish its pose";
  if (noEkf()) {
    EXPECT_EQ(loaded.count("/localization/ekf"), 0u) << "ekf:=false still loads the EKF";
    EXPECT_EQ(g.publishers["/localization/odometry"].size(), 0u)
        << "somebody publishes our EKF's odometry";
    EXPECT_EQ(g.subscribers["/localization/odometry"].count(kManager), 0u)
        << "the matcher still reads the EKF's topic";
    EXPECT_EQ(g.publishers["/odometry/filtered"].count(kManager), 0u);
  } else {
    EXPECT_EQ(g.publishers["/localization/odometry"].count(kManager), 1u);
    EXPECT_EQ(g.subscribers["/localization/pose"].count(kManager), 1u) << "the EKF's input";
    bool publish_tf = true;
    EXPECT_TRUE(ros::param::get("/localization/ekf/publish_tf", publish_tf));
    EXPECT_FALSE(publish_tf) << "ekf_publish_tf:=false did not reach the EKF";
  }
}

TEST(VehicleExternalFilter, LocalizesWithTheOtherNodesTf) {
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
  ASSERT_TRUE(outputs->mapReadySince(since, 30.0)) << "no map around /initialpose";
  player->play();
  ASSERT_TRUE(waitFor([] { return player->elapsed() >= kPlayS || player->finished(); }, 60.0));
  const double played_at = wallNow();
  ros::WallDuration(1.0).sleep();  // the last scans' matches (and the map server's period)
  const Truth truth = player->truth();
  player.reset();  // stops playing

  size_t accepted = 0, from_filter = 0;
  outputs->locked([&] {
    for (const MatchStatus& s : outputs->statuses_) {
      accepted += s.accepted;
      from_filter += s.accepted && s.prior_source == "ekf";
    }
    return 0;
  });
  std::printf("[vehicle_external_filter %s] %zu matches accepted, %zu from the filter's prior\n",
              mode.c_str(), accepted, from_filter);
  EXPECT_GE(accepted, static_cast<size_t>(0.6 * 10.0 * kPlayS));
  EXPECT_GE(from_filter, accepted / 2) << "matches did not take the filter's prior";

  {
    std::lock_guard<std::mutex> lock(relay_mutex);
    EXPECT_GT(map_odom_sent, 10u) << "the stand-in sent no map -> odom";
    EXPECT_EQ(map_odom_publishers, std::set<std::string>{ros::this_node::getName()})
        << "another node broadcasts map -> odom";
  }
  EXPECT_TRUE(outputs->sawDiagnostic(
      kPositionDiag,
      [](const diagnostic_msgs::DiagnosticStatus& s) {
        for (const auto& kv : s.values) {
          if (kv.key == "source") return kv.value == "tf";
        }
        return false;
      },
      played_at - 5.0))
      << "the map server did not follow TF map -> base_link";

  PoseError match_error;
  outputs->locked([&] {
    for (auto it = outputs->poses_.rbegin(); it != outputs->poses_.rend() && !match_error.valid();
         ++it) {
      match_error = poseError(truth, it->header.stamp.toSec(), toPose(it->pose.pose));
    }
    return 0;
  });
  ASSERT_TRUE(match_error.valid()) << "no match pose within the ground truth's time span";
  std::printf("[vehicle_external_filter %s] final match error %.3f m, %.3f deg\n", mode.c_str(),
              match_error.xy_m, match_error.yaw_rad * 180.0 / M_PI);
  EXPECT_LE(match_error.xy_m, kTolXyM);
  EXPECT_LE(match_error.yaw_rad, kTolYawRad);
  if (!noEkf()) expectEndsLocalized(*outputs, truth, "vehicle_ekf_no_tf", kTolXyM, kTolYawRad);
  outputs->locked([&] {
    EXPECT_FALSE(outputs->non_finite_) << outputs->non_finite_what_;
    EXPECT_EQ(outputs->odometry_.empty(), noEkf()) << "/localization/odometry";
    return 0;
  });
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
  if (!ros::param::get("~bag", bag) || !ros::param::get("~mode", mode) ||
      (mode != "no_ekf" && mode != "ekf_no_tf") ||
      (mode == "no_ekf" && !ros::param::get("~robot_localization_config", config_path))) {
    std::fprintf(stderr,
                 "needs ~bag (fixture.yaml), ~mode (no_ekf or ekf_no_tf) and, with no_ekf, "
                 "~robot_localization_config\n");
    return 1;
  }
  outputs = std::make_unique<vehicle_test::Outputs>(nh, /*subscribe_truth=*/false);
  player = std::make_unique<vehicle_test::FaultyPlayer>(nh, bag, vehicle_test::Faults{});
  tf_buffer = std::make_unique<tf2_ros::Buffer>();
  tf_listener = std::make_unique<tf2_ros::TransformListener>(*tf_buffer, nh);
  tf_broadcaster = std::make_unique<tf2_ros::TransformBroadcaster>();
  initialpose_pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1);
  ros::Subscriber tf_sub = nh.subscribe("/tf", 5000, onTf);
  ros::Subscriber relay_sub;
  if (mode == "no_ekf") {
    filtered_pub = nh.advertise<nav_msgs::Odometry>("/odometry/filtered", 20);
    relay_sub = nh.subscribe("/localization/pose", 20, onPose);
  } else {
    relay_sub = nh.subscribe("/localization/odometry", 500, onEkfOdometry);
  }
  const int result = RUN_ALL_TESTS();
  relay_sub.shutdown();
  tf_sub.shutdown();
  player.reset();
  spinner.stop();
  outputs.reset();
  tf_listener.reset();
  return result;
}
