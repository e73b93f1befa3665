// rostest of launch/localization.launch on a real INS driver's output through the INS adapter
// (vehicle_ins_adapter.test: ins_adapter:=true ins_driver:=autoware_lvx
// odom_topic:=/applanix/lvx_client/odom). This node plays the first kPlayS seconds of the
// fixture's drive on sim time, but instead of the bag's REP-105 /ins/odom and its TF
// odom -> base_link it publishes what Autoware's applanix_driver lvx_client publishes for the
// same motion (conversions.cpp toOdometry, as test/ros/ins_adapter_test.cpp builds it): frame
// "ned", child "POS_REF" (the POS reference point, at a lever arm from base_link given by
// /tf_static), NED position from the first fix, the tf2 setEuler(heading, pitch, roll)
// quaternion, the NED velocity of POS_REF and its FRD rates as floats, the velocity RMS only.
// Checked: the adapter runs in the manager, reads the driver topic and feeds
// /localization/ins_odom to the matcher and the EKF (master graph); its twist in base_link
// equals the bag's INS twist; TF odom -> base_link comes from the manager alone; every message
// was converted (none waited for TF); the drive ends localized within 0.3 m / 1 deg (EKF and
// last match); nothing non-finite.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <nodelet/NodeletList.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/LinearMath/Quaternion.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include "gmm_localization/core/filter/ins_frames.h"
#include "vehicle_test_support.h"

namespace gmm_localization {
namespace node {
namespace {

using namespace vehicle_test;  // NOLINT: test code

const char* kManager = "/localization/localization_manager";
const char* kAdapterDiag = "/localization/ins_adapter: INS adapter";
const char* kChild = "POS_REF";
constexpr double kPlayS = 14.0;  ///< bag seconds played (of 20): keeps the test near 25 s

std::string driver_topic;  ///< the driver's odometry topic (odom_topic of the launch)

double wallNow() { return ros::WallTime::now().toSec(); }

/// The POS reference point in base_link (TF base_link -> POS_REF): on the IMU, ahead of and
/// above the rear axle, 1 deg off (as in test/ros/ins_adapter_test.cpp).
Eigen::Isometry3d baseTChild() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.0175, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1.35, 0.3, 1.45);
  return T;
}

double f32(double x) { return static_cast<double>(static_cast<float>(x)); }
double wrap2pi(double a) {
  a = std::fmod(a, 2 * M_PI);
  return a < 0 ? a + 2 * M_PI : a;
}

/// lvx_client's odometry for the motion of a REP-105 INS message (pose odom -> base_link, twist
/// of base_link in base_link); `first_child_enu`: POS_REF's position at the first message.
nav_msgs::Odometry lvxMessage(const nav_msgs::Odometry& ins,
                              const Eigen::Vector3d& first_child_enu) {
  const Eigen::Isometry3d base_T_child = baseTChild();
  const Eigen::Isometry3d world_T_base = fromMsg(ins.pose.pose);
  const Eigen::Isometry3d world_T_child = world_T_base * base_T_child;
  const auto& tl = ins.twist.twist.linear;
  const auto& ta = ins.twist.twist.angular;
  const Eigen::Vector3d v_base(tl.x, tl.y, tl.z), w_base(ta.x, ta.y, ta.z);
  const Eigen::Vector3d p = base_T_child.translation();
  // The reference point's velocity in the world and its rates in its own (FLU) axes.
  const Eigen::Vector3d v_child_enu = world_T_base.linear() * (v_base + w_base.cross(p));
  const Eigen::Vector3d w_child = base_T_child.linear().transpose() * w_base;
  // Applanix angles of FRD in NED.
  const Eigen::Matrix3d ned_R_frd = enuFromNed() * world_T_child.linear() * fluFromFrd();
  const double heading = wrap2pi(std::atan2(ned_R_frd(1, 0), ned_R_frd(0, 0)));
  const double pitch = -std::asin(std::clamp(ned_R_frd(2, 0), -1.0, 1.0));
  const double roll = std::atan2(ned_R_frd(2, 1), ned_R_frd(2, 2));
  const Eigen::Vector3d ned_position =
      enuFromNed() * (world_T_child.translation() - first_child_enu);
  const Eigen::Vector3d ned_velocity = enuFromNed() * v_child_enu;
  const Eigen::Vector3d frd_rates = fluFromFrd() * w_child;

  nav_msgs::Odometry odom;
  odom.header.stamp = ins.header.stamp;
  odom.header.frame_id = "ned";
  odom.child_frame_id = kChild;
  odom.pose.pose.position.x = ned_position.x();
  odom.pose.pose.position.y = ned_position.y();
  odom.pose.pose.position.z = ned_position.z();
  tf2::Quaternion q;
  q.setEuler(heading, pitch, roll);
  odom.pose.pose.orientation.x = q.x();
  odom.pose.pose.orientation.y = q.y();
  odom.pose.pose.orientation.z = q.z();
  odom.pose.pose.orientation.w = q.w();
  odom.twist.twist.linear.x = f32(ned_velocity.x());
  odom.twist.twist.linear.y = f32(ned_velocity.y());
  odom.twist.twist.linear.z = f32(ned_velocity.z());
  const double deg = 180.0 / M_PI;  // the rates travel as float deg/s
  odom.twist.twist.angular.x = f32(frd_rates.x() * deg) / deg;
  odom.twist.twist.angular.y = f32(frd_rates.y() * deg) / deg;
  odom.twist.twist.angular.z = f32(frd_rates.z() * deg) / deg;
  // GSOF 50 RMS: position, attitude and velocity; no rate covariance (the adapter's default).
  const double pos_rms = 0.02, vel_rms = 0.02, att_rms = 0.02 / deg;
  odom.pose.covariance[0] = odom.pose.covariance[7] = pos_rms * pos_rms;
  odom.pose.covariance[14] = 4 * pos_rms * pos_rms;
  odom.pose.covariance[21] = odom.pose.covariance[28] = att_rms * att_rms;
  odom.pose.covariance[35] = 4 * att_rms * att_rms;
  odom.twist.covariance[0] = odom.twist.covariance[7] = vel_rms * vel_rms;
  odom.twist.covariance[14] = vel_rms * vel_rms;
  return odom;
}

/// Plays the bag on sim time (rate 1, like `rosbag play --clock`) with the INS as the driver
/// publishes it: /velodyne_points, /imu/data and the driver's odometry; /tf_static (latched) is
/// the bag's plus base_link -> POS_REF. The bag's TF odom -> base_link is not played: the
/// adapter broadcasts it.
class DriverPlayer {
 public:
  DriverPlayer(ros::NodeHandle& nh, const std::string& bag_path) {
    bag_.open(bag_path, rosbag::bagmode::Read);
    rosbag::View all(bag_);
    start_ = all.getBeginTime();
    rosbag::View in(bag_, rosbag::TopicQuery(std::vector<std::string>{"/ground_truth/odom",
                                                                      "/ins/odom", "/tf_static"}));
    for (const rosbag::MessageInstance& m : in) {
      if (m.getTopic() == "/tf_static") {
        if (auto st = m.instantiate<tf2_msgs::TFMessage>()) {
          statics_.transforms.insert(statics_.transforms.end(), st->transforms.begin(),
                                     st->transforms.end());
        }
      } else if (auto odom = m.instantiate<nav_msgs::Odometry>()) {
        if (m.getTopic() == "/ins/odom") {
          ins_twist_[odom->header.stamp.toNSec()] = odom->twist.twist;
        } else {
          truth_.add(odom->header.stamp.toSec(), toPose(odom->pose.pose));
        }
      }
    }
    geometry_msgs::TransformStamped lever;
    lever.header.stamp = start_;
    lever.header.frame_id = "base_link";
    lever.child_frame_id = kChild;
    toMsg(baseTChild(), lever.transform);
    statics_.transforms.push_back(lever);

    clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    scan_pub_ = nh.advertise<sensor_msgs::PointCloud2>("/velodyne_points", 2);
    imu_pub_ = nh.advertise<sensor_msgs::Imu>("/imu/data", 200);
    driver_pub_ = nh.advertise<nav_msgs::Odometry>(driver_topic, 100);
    tf_static_pub_ = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, /*latch=*/true);
    tf_static_pub_.publish(statics_);
  }
  ~DriverPlayer() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

  const Truth& truth() const { return truth_; }
  ros::Time start() const { return start_; }
  double elapsed() const { return elapsed_.load(); }
  size_t driverMessages() const { return driver_messages_.load(); }
  /// The bag's INS twist (base_link) at exactly `stamp`, if it has a message there.
  const geometry_msgs::Twist* insTwistAt(const ros::Time& stamp) const {
    const auto it = ins_twist_.find(stamp.toNSec());
    return it == ins_twist_.end() ? nullptr : &it->second;
  }

  void publishStartClock() {
    rosgraph_msgs::Clock c;
    c.clock = start_;
    clock_pub_.publish(c);
  }
  /// Plays the first `duration_s` seconds (wall pacing from now).
  void play(double duration_s) {
    thread_ = std::thread([this, duration_s] { run(duration_s); });
  }
  /// Stops playing.
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  void run(double duration_s) {
    rosbag::View view(bag_, rosbag::TopicQuery(std::vector<std::string>{"/velodyne_points",
                                                                        "/ins/odom", "/imu/data"}));
    const ros::WallTime wall_start = ros::WallTime::now();
    std::optional<Eigen::Vector3d> first_child;
    for (const rosbag::MessageInstance& m : view) {
      const double rel = (m.getTime() - start_).toSec();
      if (rel > duration_s) break;
      while (!stop_ && ros::ok()) {
        const double wait = rel - (ros::WallTime::now() - wall_start).toSec();
        if (wait <= 0.0) break;
        ros::WallDuration(std::min(wait, 0.01)).sleep();
      }
      if (stop_ || !ros::ok()) break;
      rosgraph_msgs::Clock c;
      c.clock = m.getTime();
      clock_pub_.publish(c);
      elapsed_ = rel;
      if (m.getTopic() == "/velodyne_points") {
        scan_pub_.publish(m.instantiate<sensor_msgs::PointCloud2>());
      } else if (m.getTopic() == "/imu/data") {
        imu_pub_.publish(m.instantiate<sensor_msgs::Imu>());
      } else if (auto ins = m.instantiate<nav_msgs::Odometry>()) {
        if (!first_child) first_child = (fromMsg(ins->pose.pose) * baseTChild()).translation();
        driver_pub_.publish(lvxMessage(*ins, *first_child));
        ++driver_messages_;
      }
    }
    elapsed_ = duration_s;
  }

  rosbag::Bag bag_;
  Truth truth_;
  ros::Time start_;
  tf2_msgs::TFMessage statics_;
  std::map<uint64_t, geometry_msgs::Twist> ins_twist_;  ///< by stamp [ns]
  ros::Publisher clock_pub_, scan_pub_, imu_pub_, driver_pub_, tf_static_pub_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<double> elapsed_{0.0};
  std::atomic<size_t> driver_messages_{0};
};

std::unique_ptr<Outputs> outputs;
std::unique_ptr<DriverPlayer> player;
ros::Publisher initialpose_pub;

std::mutex seen_mutex;
std::vector<nav_msgs::Odometry> ins_odom;    ///< the adapter's output
std::set<std::string> odom_base_publishers;  ///< callers seen broadcasting odom -> base_link

void onInsOdom(const nav_msgs::Odometry::ConstPtr& m) {
  std::lock_guard<std::mutex> lock(seen_mutex);
  ins_odom.push_back(*m);
}

void onTf(const ros::MessageEvent<const tf2_msgs::TFMessage>& event) {
  for (const auto& t : event.getConstMessage()->transforms) {
    if (t.header.frame_id == "odom" && t.child_frame_id == "base_link") {
      std::lock_guard<std::mutex> lock(seen_mutex);
      odom_base_publishers.insert(event.getPublisherName());
    }
  }
}

TEST(VehicleInsAdapter, TheAdapterFeedsTheMatcherAndTheEkf) {
  ASSERT_TRUE(ros::service::waitForService(std::string(kManager) + "/list", 30000));
  nodelet::NodeletList list;
  std::set<std::string> loaded;
  ASSERT_TRUE(waitFor(
      [&] {
        if (!ros::service::call(std::string(kManager) + "/list", list)) return false;
        loaded =
            std::set<std::string>(list.response.nodelets.begin(), list.response.nodelets.end());
        return loaded.count("/localization/ins_adapter") && loaded.count("/localization/matcher") &&
               loaded.count("/localization/ekf") && loaded.count("/localization/map_server");
      },
      30.0))
      << "nodelets loaded: " << loaded.size();
  Graph g;
  ASSERT_TRUE(waitFor(
      [&] {
        g = Graph();
        return readGraph(&g) && g.subscribers[driver_topic].count(kManager) == 1 &&
               g.publishers["/localization/ins_odom"].count(kManager) == 1 &&
               g.subscribers["/localization/ins_odom"].count(kManager) == 1;
      },
      30.0))
      << "the manager does not read " << driver_topic << " or not /localization/ins_odom";
  EXPECT_EQ(g.subscribers["/ins/odom"].count(kManager), 0u) << "something reads the default";
  std::string preset;
  EXPECT_TRUE(ros::param::get("/localization/ins_adapter/driver_preset", preset));
  EXPECT_EQ(preset, "autoware_lvx");
}

TEST(VehicleInsAdapter, LocalizesOnTheDriversOutput) {
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
  p.x -= 1.5;
  p.y += 2.0;
  p.yaw -= 2.0 * M_PI / 180.0;
  p.z = p.roll = p.pitch = 0.0;
  start.pose.pose = toMsg(p);
  start.pose.covariance[0] = start.pose.covariance[7] = 0.25;
  start.pose.covariance[35] = 0.0076;
  initialpose_pub.publish(start);
  ASSERT_TRUE(outputs->mapReadySince(since, 30.0)) << "no map around /initialpose";
  player->play(kPlayS);
  ASSERT_TRUE(waitFor([] { return player->elapsed() >= kPlayS; }, 60.0));
  const double played_at = wallNow();
  ros::WallDuration(1.5).sleep();  // the last matches, a fresh adapter diagnostic
  player->stop();

  // The adapter's output: REP-105 frames, the twist of base_link the bag's INS reported.
  size_t compared = 0;
  double max_dv = 0.0, max_dw = 0.0;
  {
    std::lock_guard<std::mutex> lock(seen_mutex);
    ASSERT_FALSE(ins_odom.empty()) << "no /localization/ins_odom";
    for (const nav_msgs::Odometry& o : ins_odom) {
      EXPECT_EQ(o.header.frame_id, "odom");
      EXPECT_EQ(o.child_frame_id, "base_link");
      const geometry_msgs::Twist* bag = player->insTwistAt(o.header.stamp);
      if (bag == nullptr) continue;
      ++compared;
      const auto& v = o.twist.twist.linear;
      const auto& w = o.twist.twist.angular;
      max_dv = std::max({max_dv, std::abs(v.x - bag->linear.x), std::abs(v.y - bag->linear.y),
                         std::abs(v.z - bag->linear.z)});
      max_dw = std::max({max_dw, std::abs(w.x - bag->angular.x), std::abs(w.y - bag->angular.y),
                         std::abs(w.z - bag->angular.z)});
    }
    EXPECT_EQ(odom_base_publishers, std::set<std::string>{kManager})
        << "odom -> base_link must come from the adapter alone";
  }
  std::printf(
      "[vehicle_ins_adapter] %zu driver messages, %zu converted compared: max twist "
      "error %.2e m/s, %.2e rad/s\n",
      player->driverMessages(), compared, max_dv, max_dw);
  EXPECT_GE(compared, player->driverMessages() * 9 / 10);
  EXPECT_LE(max_dv, 1e-3);  // float velocities and rates: ~1e-6 relative
  EXPECT_LE(max_dw, 1e-4);
  EXPECT_EQ(outputs->diagnosticValue(kAdapterDiag, "dropped: no TF"), "0");
  EXPECT_EQ(outputs->diagnosticValue(kAdapterDiag, "dropped: invalid"), "0");
  const std::string sent = std::to_string(player->driverMessages());
  EXPECT_TRUE(waitFor(
      [&] { return outputs->diagnosticValue(kAdapterDiag, "messages published") == sent; }, 5.0))
      << "the adapter published " << outputs->diagnosticValue(kAdapterDiag, "messages published")
      << " of " << sent;
  EXPECT_TRUE(outputs->sawDiagnostic(
      kAdapterDiag,
      [](const diagnostic_msgs::DiagnosticStatus& s) {
        for (const auto& kv : s.values) {
          if (kv.key == "child frame") return kv.value == kChild;
        }
        return false;
      },
      played_at - 5.0));

  size_t accepted = 0;
  outputs->locked([&] {
    for (const MatchStatus& s : outputs->statuses_) accepted += s.accepted;
    return 0;
  });
  EXPECT_GE(accepted, static_cast<size_t>(0.6 * 10.0 * kPlayS));
  expectEndsLocalized(*outputs, player->truth(), "vehicle_ins_adapter", kTolXyM, kTolYawRad);
  PoseError match_error;
  outputs->locked([&] {
    for (auto it = outputs->poses_.rbegin(); it != outputs->poses_.rend() && !match_error.valid();
         ++it) {
      match_error = poseError(player->truth(), it->header.stamp.toSec(), toPose(it->pose.pose));
    }
    return 0;
  });
  ASSERT_TRUE(match_error.valid());
  std::printf("[vehicle_ins_adapter] %zu matches accepted, last %.3f m, %.3f deg\n", accepted,
              match_error.xy_m, match_error.yaw_rad * 180.0 / M_PI);
  EXPECT_LE(match_error.xy_m, kTolXyM);
  EXPECT_LE(match_error.yaw_rad, kTolYawRad);
  expectNothingNonFinite(*outputs);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "vehicle_ins_adapter_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  using namespace gmm_localization::node;  // NOLINT: test code
  std::string bag;
  if (!ros::param::get("~bag", bag) || !ros::param::get("~driver_topic", driver_topic)) {
    std::fprintf(stderr, "needs ~bag (fixture.yaml) and ~driver_topic\n");
    return 1;
  }
  outputs = std::make_unique<vehicle_test::Outputs>(nh, /*subscribe_truth=*/false);
  player = std::make_unique<DriverPlayer>(nh, bag);
  initialpose_pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1);
  ros::Subscriber ins_sub = nh.subscribe("/localization/ins_odom", 5000, onInsOdom);
  ros::Subscriber tf_sub = nh.subscribe("/tf", 5000, onTf);
  const int result = RUN_ALL_TESTS();
  ins_sub.shutdown();
  tf_sub.shutdown();
  player.reset();
  spinner.stop();
  outputs.reset();
  return result;
}
