// The INS adapter (ros/ins_adapter_conversion.h) on bags shaped like the two Applanix drivers in
// use, written here with the rosbag API and read back: the vehicle of test/unit/support/
// ins_circle.h drives a full circle with the INS at a lever arm; the adapter's twist in base_link
// equals the truth, its odometry ends where the vehicle does. The messages are built as the
// drivers' sources build them (docs/ros.md, "INS drivers"):
//  - Autoware's applanix_driver lvx_client (autowarefoundation/applanix, conversions.cpp
//    toOdometry): frame "ned", child "POS_REF"; position NED; orientation
//    tf2::Quaternion::setEuler(heading, pitch, roll); linear = (north, east, down) velocity
//    (float); angular = rates about the FRD axes (float, deg/s -> rad/s); covariance from the
//    GSOF 50 RMS.
//  - Clearpath's applanix_bridge (clearpathrobotics/applanix_driver, publisher.py): frame
//    "odom_combined", child "base_footprint"; position UTM east/north/up from the first fix;
//    orientation RPY(roll, -pitch, 90 deg - heading); linear = (east, north, -down) velocity;
//    angular = (long, -trans, -down) rates; fixed covariances.
// No master: the adapter is fed the bag's messages and a tf2::BufferCore filled from its
// /tf_static.
#include "gmm_localization/ros/ins_adapter_conversion.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_msgs/TFMessage.h>

#include "../unit/support/ins_circle.h"
#include "../unit/support/temp_dir.h"
#include "gmm_localization/ros/ekf_node_conversions.h"
#include "gmm_localization/ros/ins_adapter_options.h"
#include "gmm_localization/ros/params.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

using test::InsCircle;

constexpr double kT0 = 1.7e9;      // bag stamps [s]
constexpr double kRateHz = 100.0;  // both drivers: the GSOF 49 / group 1 rate of a POS LV

enum class Driver { kAutowareLvx, kClearpathBridge };

struct DriverShape {
  std::string topic, frame, child;
  Eigen::Isometry3d base_T_child;
};

DriverShape shape(Driver d) {
  DriverShape s;
  s.base_T_child = Eigen::Isometry3d::Identity();
  if (d == Driver::kAutowareLvx) {
    s.topic = "/applanix/lvx_client/odom";
    s.frame = "ned";
    s.child = "POS_REF";
    // The POS LV reference point: on the IMU, ahead of and above the rear axle, 1 deg off.
    s.base_T_child.linear() =
        Eigen::AngleAxisd(0.0175, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    s.base_T_child.translation() = Eigen::Vector3d(1.35, 0.3, 1.45);
  } else {
    s.topic = "/gps_odom";
    s.frame = "odom_combined";
    s.child = "base_footprint";
    s.base_T_child.translation() = Eigen::Vector3d(0.0, 0.0, -0.35);  // on the ground
  }
  return s;
}

InsCircle circle(const DriverShape& s) {
  InsCircle c;
  c.base_T_child = s.base_T_child;
  return c;
}

double wrap2pi(double a) {
  a = std::fmod(a, 2 * M_PI);
  return a < 0 ? a + 2 * M_PI : a;
}

/// The Applanix angles [rad] and FRD rates the POS reports for the child frame at t.
struct PosSolution {
  double roll, pitch, heading;  // heading 0 .. 2 pi, as the POS gives 0 .. 360 deg
  Eigen::Vector3d ned_position, ned_velocity, frd_rates;
};

PosSolution solution(const InsCircle& c, double t) {
  const Eigen::Isometry3d child = c.childPose(t);
  const Eigen::Matrix3d ned_R_frd = enuFromNed() * child.linear() * fluFromFrd();
  PosSolution p;
  p.heading = wrap2pi(std::atan2(ned_R_frd(1, 0), ned_R_frd(0, 0)));
  p.pitch = -std::asin(ned_R_frd(2, 0));
  p.roll = std::atan2(ned_R_frd(2, 1), ned_R_frd(2, 2));
  p.ned_position = enuFromNed() * (child.translation() - c.childPose(0.0).translation());
  p.ned_velocity = enuFromNed() * c.childWorldVelocity(t);
  p.frd_rates = fluFromFrd() * c.childRates(t);
  return p;
}

/// Stamps at t after kT0, exact to the nanosecond (kT0 + t as a double is not: 0.24 us steps).
ros::Time stampAt(double t) { return ros::Time(kT0) + ros::Duration(t); }

double f32(double x) { return static_cast<double>(static_cast<float>(x)); }

/// applanix_driver_ros::toOdometry(ins_solution, local_cartesian, ins_solution_rms) at time t.
nav_msgs::Odometry autowareMessage(const DriverShape& s, const PosSolution& p, double t) {
  nav_msgs::Odometry odom;
  odom.header.stamp = stampAt(t);
  odom.header.frame_id = s.frame;
  odom.child_frame_id = s.child;
  odom.pose.pose.position.x = p.ned_position.x();
  odom.pose.pose.position.y = p.ned_position.y();
  odom.pose.pose.position.z = p.ned_position.z();
  tf2::Quaternion q;
  q.setEuler(p.heading, p.pitch, p.roll);
  odom.pose.pose.orientation.x = q.x();
  odom.pose.pose.orientation.y = q.y();
  odom.pose.pose.orientation.z = q.z();
  odom.pose.pose.orientation.w = q.w();
  odom.twist.twist.linear.x = f32(p.ned_velocity.x());
  odom.twist.twist.linear.y = f32(p.ned_velocity.y());
  odom.twist.twist.linear.z = f32(p.ned_velocity.z());
  const double deg = 180.0 / M_PI;  // the rates travel as float deg/s
  odom.twist.twist.angular.x = f32(p.frd_rates.x() * deg) / deg;
  odom.twist.twist.angular.y = f32(p.frd_rates.y() * deg) / deg;
  odom.twist.twist.angular.z = f32(p.frd_rates.z() * deg) / deg;
  const double pos_rms = 0.02, vel_rms = 0.015, att_rms = 0.02 / deg;
  odom.pose.covariance[0] = odom.pose.covariance[7] = pos_rms * pos_rms;
  odom.pose.covariance[14] = 4 * pos_rms * pos_rms;
  odom.pose.covariance[21] = odom.pose.covariance[28] = att_rms * att_rms;
  odom.pose.covariance[35] = 4 * att_rms * att_rms;
  odom.twist.covariance[0] = odom.twist.covariance[7] = vel_rms * vel_rms;
  odom.twist.covariance[14] = 4 * vel_rms * vel_rms;
  return odom;
}

/// ApplanixPublisher.navigation_handler (zero_start: UTM from the first fix) at time t.
nav_msgs::Odometry clearpathMessage(const DriverShape& s, const PosSolution& p, double t) {
  nav_msgs::Odometry odom;
  odom.header.stamp = stampAt(t);
  odom.header.frame_id = s.frame;
  odom.child_frame_id = s.child;
  const Eigen::Vector3d enu = enuFromNed() * p.ned_position;
  odom.pose.pose.position.x = enu.x();
  odom.pose.pose.position.y = enu.y();
  odom.pose.pose.position.z = enu.z();
  tf2::Quaternion q;  // PyKDL.Rotation.RPY(roll, -pitch, 90 - heading): fixed axes X, Y, Z
  q.setRPY(p.roll, -p.pitch, M_PI / 2 - p.heading);
  odom.pose.pose.orientation.x = q.x();
  odom.pose.pose.orientation.y = q.y();
  odom.pose.pose.orientation.z = q.z();
  odom.pose.pose.orientation.w = q.w();
  odom.twist.twist.linear.x = p.ned_velocity.y();   // east_vel
  odom.twist.twist.linear.y = p.ned_velocity.x();   // north_vel
  odom.twist.twist.linear.z = -p.ned_velocity.z();  // -down_vel
  odom.twist.twist.angular.x = p.frd_rates.x();     // ang_rate_long
  odom.twist.twist.angular.y = -p.frd_rates.y();    // -ang_rate_trans
  odom.twist.twist.angular.z = -p.frd_rates.z();    // -ang_rate_down
  for (int i = 0; i < 6; ++i) {
    odom.pose.covariance[7 * i] = i < 3 ? 1.0 : 0.1;   // POSE_COVAR
    odom.twist.covariance[7 * i] = i < 3 ? 1.0 : 0.1;  // TWIST_COVAR
  }
  return odom;
}

/// A bag of `duration` s of the driver's odometry and its /tf_static (base_link -> child).
void writeBag(const std::string& path, Driver d, double duration, bool with_tf = true) {
  const DriverShape s = shape(d);
  const InsCircle c = circle(s);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  if (with_tf) {
    tf2_msgs::TFMessage st;
    geometry_msgs::TransformStamped t;
    t.header.stamp.fromSec(kT0 - 0.5);
    t.header.frame_id = "base_link";
    t.child_frame_id = s.child;
    toMsg(s.base_T_child, t.transform);
    st.transforms.push_back(t);
    bag.write("/tf_static", ros::Time(kT0 - 0.5), st);  // latched: recorded first
  }
  const int n = static_cast<int>(std::lround(duration * kRateHz));
  for (int i = 0; i <= n; ++i) {
    const double t = i * duration / n;
    const PosSolution p = solution(c, t);
    const nav_msgs::Odometry m =
        d == Driver::kAutowareLvx ? autowareMessage(s, p, t) : clearpathMessage(s, p, t);
    bag.write(s.topic, m.header.stamp, m);
  }
  bag.close();
}

InsAdapterOptions options(const std::string& preset) {
  XmlRpc::XmlRpcValue tree;
  tree["driver_preset"] = preset;
  return loadInsAdapterOptions(ParamSource::fromTree(tree, "test:"));
}

struct Replay {
  std::vector<InsAdapterResult> results;
  std::vector<double> t;  // truth time of each result
};

/// Plays the bag through the adapter: /tf_static into a BufferCore, the odometry through it.
Replay replay(const std::string& path, const std::string& topic, InsOdometryAdapter& adapter) {
  tf2::BufferCore tf;
  Replay r;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto st = m.instantiate<tf2_msgs::TFMessage>()) {
      for (const auto& t : st->transforms) tf.setTransform(t, "bag", /*is_static=*/true);
    } else if (auto odom = m.instantiate<nav_msgs::Odometry>()) {
      EXPECT_EQ(m.getTopic(), topic);
      r.results.push_back(adapter.process(*odom, tf));
      r.t.push_back((odom->header.stamp - ros::Time(kT0)).toSec());
    }
  }
  return r;
}

Eigen::Matrix<double, 6, 1> twistOf(const nav_msgs::Odometry& o) {
  Eigen::Matrix<double, 6, 1> x;
  x << o.twist.twist.linear.x, o.twist.twist.linear.y, o.twist.twist.linear.z,
      o.twist.twist.angular.x, o.twist.twist.angular.y, o.twist.twist.angular.z;
  return x;
}

/// Replays a full circle of the driver's bag through its preset and checks every output.
void checkDriver(Driver d, const std::string& preset) {
  testing::TempDir dir("gmm_ins_adapter");
  const std::string path = dir.path + "/ins.bag";
  const DriverShape s = shape(d);
  const InsCircle c = circle(s);
  const double full_circle = 2 * M_PI / c.yaw_rate;
  writeBag(path, d, full_circle);
  InsOdometryAdapter adapter(options(preset));
  const Replay r = replay(path, s.topic, adapter);
  ASSERT_EQ(r.results.size(), static_cast<size_t>(std::lround(full_circle * kRateHz)) + 1);
  double worst_v = 0.0, worst_w = 0.0;
  for (size_t i = 0; i < r.results.size(); ++i) {
    const InsAdapterResult& out = r.results[i];
    ASSERT_EQ(out.outcome, InsAdapterOutcome::kPublished) << out.reason;
    EXPECT_EQ(out.child_frame, s.child);
    EXPECT_EQ(out.odometry.header.frame_id, "odom");
    EXPECT_EQ(out.odometry.child_frame_id, "base_link");
    EXPECT_EQ(out.transform.header.frame_id, "odom");
    EXPECT_EQ(out.transform.child_frame_id, "base_link");
    EXPECT_EQ(out.transform.header.stamp, out.odometry.header.stamp);
    const Eigen::Matrix<double, 6, 1> err = twistOf(out.odometry) - c.bodyTwist(r.t[i]);
    worst_v = std::max(worst_v, err.head<3>().norm());
    worst_w = std::max(worst_w, err.tail<3>().norm());
  }
  // Float velocities and rates (Autoware's driver) limit the agreement to ~1e-6.
  EXPECT_LT(worst_v, 1e-5) << preset;
  EXPECT_LT(worst_w, 1e-6) << preset;
  // Forward at 10 m/s, no sideslip, yaw rate 0.2 rad/s: what the EKF needs.
  const nav_msgs::Odometry& last = r.results.back().odometry;
  EXPECT_NEAR(last.twist.twist.linear.x, 10.0, 1e-5);
  EXPECT_NEAR(last.twist.twist.linear.y, 0.0, 1e-5);
  // Dead reckoning around the circle ends at the truth (odom: ENU at the first position).
  const Eigen::Isometry3d end = fromMsg(last.pose.pose);
  Eigen::Isometry3d truth = c.pose(full_circle);
  truth.translation() -= c.position(0.0);
  EXPECT_LT((end.translation() - truth.translation()).norm(), 1e-3)
      << end.translation().transpose() << " vs " << truth.translation().transpose();
  EXPECT_LT(Eigen::AngleAxisd(end.linear().transpose() * truth.linear()).angle(), 1e-6);
  EXPECT_TRUE(fromMsg(r.results.back().transform.transform).isApprox(end, 1e-12));
  // The twist covariance is in base_link, symmetric, positive definite.
  const Matrix6d cov = covarianceFromMsg(last.twist.covariance);
  EXPECT_TRUE(cov.isApprox(cov.transpose()));
  EXPECT_GT(cov.ldlt().vectorD().minCoeff(), 0.0);
}

TEST(InsAdapter, AutowareLvxBagGivesTheBaseLinkTwist) {
  checkDriver(Driver::kAutowareLvx, "autoware_lvx");
}

TEST(InsAdapter, ClearpathApplanixBridgeBagGivesTheBaseLinkTwist) {
  checkDriver(Driver::kClearpathBridge, "clearpath_applanix_bridge");
}

TEST(InsAdapter, TheDriversTwistReadAsREP105IsWrong) {
  // What the EKF and the matcher did with these drivers before: the raw twist as body twist.
  for (Driver d : {Driver::kAutowareLvx, Driver::kClearpathBridge}) {
    testing::TempDir dir("gmm_ins_adapter");
    const std::string path = dir.path + "/ins.bag";
    const DriverShape s = shape(d);
    writeBag(path, d, 5.0);
    InsOdometryAdapter rep105(options("rep105"));
    const Replay r = replay(path, s.topic, rep105);
    const InsCircle c = circle(s);
    double worst = 0.0;
    for (size_t i = 0; i < r.results.size(); ++i) {
      worst =
          std::max(worst, (twistOf(r.results[i].odometry) - c.bodyTwist(r.t[i])).head<3>().norm());
    }
    EXPECT_GT(worst, 5.0);  // metres per second off: the vehicle drives sideways
  }
}

TEST(InsAdapter, MessagesWaitForTheLeverArmInTf) {
  testing::TempDir dir("gmm_ins_adapter");
  const std::string path = dir.path + "/ins.bag";
  writeBag(path, Driver::kAutowareLvx, 0.5, /*with_tf=*/false);
  InsOdometryAdapter adapter(options("autoware_lvx"));
  const Replay r = replay(path, shape(Driver::kAutowareLvx).topic, adapter);
  ASSERT_FALSE(r.results.empty());
  for (const InsAdapterResult& out : r.results) {
    EXPECT_EQ(out.outcome, InsAdapterOutcome::kNoTransform);
    EXPECT_NE(out.reason.find("base_link <- POS_REF"), std::string::npos) << out.reason;
  }
  // The child frame can be named by the parameter (a driver that leaves it empty) and the lever
  // arm then comes from TF, once it is there.
  tf2::BufferCore tf;
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "base_link";
  t.child_frame_id = "ins_ref";
  t.transform.rotation.w = 1.0;
  t.transform.translation.x = 2.0;
  tf.setTransform(t, "test", true);
  InsAdapterOptions o = options("rep105");
  o.child_frame = "ins_ref";
  InsOdometryAdapter named(o);
  nav_msgs::Odometry m;
  m.header.stamp.fromSec(kT0);
  m.pose.pose.orientation.w = 1.0;
  m.twist.twist.linear.x = 5.0;
  m.twist.twist.angular.z = 0.5;
  const InsAdapterResult out = named.process(m, tf);
  ASSERT_EQ(out.outcome, InsAdapterOutcome::kPublished) << out.reason;
  EXPECT_EQ(out.child_frame, "ins_ref");
  // base_link 2 m behind the INS, turning left at 0.5 rad/s: it moves 1 m/s to the right of the
  // INS's velocity (v_base = v_ins + p x w, p = (2, 0, 0)).
  EXPECT_NEAR(out.odometry.twist.twist.linear.x, 5.0, 1e-12);
  EXPECT_NEAR(out.odometry.twist.twist.linear.y, -1.0, 1e-12);
  ASSERT_NE(named.extrinsic("ins_ref"), nullptr);
}

TEST(InsAdapter, OutOfOrderAndInvalidMessagesAreDroppedWithAReason) {
  InsOdometryAdapter adapter(options("clearpath_applanix_bridge"));
  tf2::BufferCore tf;
  const DriverShape s = shape(Driver::kClearpathBridge);
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "base_link";
  t.child_frame_id = s.child;
  toMsg(s.base_T_child, t.transform);
  tf.setTransform(t, "test", true);
  const InsCircle c = circle(s);
  auto msg = [&](double time) { return clearpathMessage(s, solution(c, time), time); };
  EXPECT_EQ(adapter.process(msg(0.0), tf).outcome, InsAdapterOutcome::kPublished);
  EXPECT_EQ(adapter.process(msg(0.01), tf).outcome, InsAdapterOutcome::kPublished);
  const InsAdapterResult repeated = adapter.process(msg(0.01), tf);
  EXPECT_EQ(repeated.outcome, InsAdapterOutcome::kOutOfOrder);
  EXPECT_NE(repeated.reason.find("not after"), std::string::npos);
  nav_msgs::Odometry bad = msg(0.02);
  bad.pose.pose.orientation = geometry_msgs::Quaternion();  // all zeros: a driver without attitude
  const InsAdapterResult invalid = adapter.process(bad, tf);
  EXPECT_EQ(invalid.outcome, InsAdapterOutcome::kInvalid);
  EXPECT_NE(invalid.reason.find("quaternion"), std::string::npos) << invalid.reason;
  EXPECT_EQ(adapter.process(msg(0.02), tf).outcome, InsAdapterOutcome::kPublished);
  // A looping bag: time back by 20 ms is dropped, by seconds restarts at the origin.
  const InsAdapterResult loop = adapter.process(msg(-5.0), tf);
  EXPECT_EQ(loop.outcome, InsAdapterOutcome::kPublished);
  EXPECT_EQ(loop.step, InsOdometryStep::kRestarted);
  EXPECT_NEAR(fromMsg(loop.odometry.pose.pose).translation().norm(), 0.0, 1e-12);
}

TEST(InsAdapter, DriverPoseSourceFollowsTheDriversPose) {
  testing::TempDir dir("gmm_ins_adapter");
  const std::string path = dir.path + "/ins.bag";
  writeBag(path, Driver::kAutowareLvx, 3.0);
  InsAdapterOptions o = options("autoware_lvx");
  o.odometry.pose_source = InsPoseSource::kDriver;
  InsOdometryAdapter adapter(o);
  const DriverShape s = shape(Driver::kAutowareLvx);
  const Replay r = replay(path, s.topic, adapter);
  const InsCircle c = circle(s);
  for (size_t i = 0; i < r.results.size(); i += 37) {
    Eigen::Isometry3d truth = c.pose(r.t[i]);
    truth.translation() -= c.position(0.0);
    EXPECT_TRUE(fromMsg(r.results[i].odometry.pose.pose).isApprox(truth, 1e-9)) << i;
    // The driver's NED position variances (north 4e-4, east 4e-4, down 1.6e-3) come out in ENU.
    EXPECT_NEAR(r.results[i].odometry.pose.covariance[14], 1.6e-3, 1e-12);
  }
}

TEST(InsAdapterOptions, PresetsAndOverrides) {
  InsAdapterOptions o = options("autoware_lvx");
  EXPECT_EQ(o.convention.velocity_frame, InsVelocityFrame::kNed);
  EXPECT_EQ(o.convention.body_axes, InsBodyAxes::kFrd);
  EXPECT_EQ(o.convention.attitude, InsAttitude::kNedSetEuler);
  o = options("clearpath_applanix_bridge");
  EXPECT_EQ(o.convention.velocity_frame, InsVelocityFrame::kEnu);
  EXPECT_EQ(o.convention.body_axes, InsBodyAxes::kFlu);
  EXPECT_EQ(o.convention.attitude, InsAttitude::kEnu);
  o = options("rep105");
  EXPECT_EQ(o.convention.velocity_frame, InsVelocityFrame::kBody);

  XmlRpc::XmlRpcValue tree;
  tree["driver_preset"] = std::string("autoware_lvx");
  tree["attitude"] = std::string("ned");  // a fixed driver that publishes a proper quaternion
  tree["pose_source"] = std::string("driver");
  o = loadInsAdapterOptions(ParamSource::fromTree(tree, "test:"));
  EXPECT_EQ(o.convention.attitude, InsAttitude::kNed);
  EXPECT_EQ(o.convention.velocity_frame, InsVelocityFrame::kNed);
  EXPECT_EQ(o.odometry.pose_source, InsPoseSource::kDriver);

  auto fails = [](const std::string& key, XmlRpc::XmlRpcValue value, const std::string& what) {
    XmlRpc::XmlRpcValue t;
    t[key] = value;
    try {
      loadInsAdapterOptions(ParamSource::fromTree(t, "test:"));
      ADD_FAILURE() << key << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  fails("driver_preset", std::string("applanix"), "must be rep105, autoware_lvx or");
  fails("velocity_frame", std::string("NED"), "test:velocity_frame = 'NED' must be body, enu");
  fails("attitude", std::string("ned_set_euler"), "body_axes must be frd");
  fails("max_gap_s", 0.0, "max_gap_s");
  fails("base_frame", std::string("odom"), "must differ");
  fails("publish_tf", std::string("yes"), "wrong type");
}

/// The shipped config/ins_adapter.yaml, read as the flat file it is ("key: value  # comment").
XmlRpc::XmlRpcValue shippedConfig() {
  std::ifstream in("config/ins_adapter.yaml");  // the tests run in the source directory
  EXPECT_TRUE(in.good());
  XmlRpc::XmlRpcValue tree;
  std::string line;
  while (std::getline(in, line)) {
    const std::string content = line.substr(0, line.find('#'));
    if (content.find_first_not_of(" \t") == std::string::npos) continue;
    EXPECT_NE(content[0], ' ') << "nested key: " << line;
    const size_t colon = content.find(':');
    EXPECT_NE(colon, std::string::npos) << line;
    const std::string key = content.substr(0, colon);
    std::string value = content.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    value.erase(value.find_last_not_of(" \t") + 1);
    if (value == "true" || value == "false") {
      tree[key] = value == "true";
    } else if (value.size() >= 2 && value.front() == '"' && value.back() == '"') {
      tree[key] = value.substr(1, value.size() - 2);
    } else {
      std::istringstream number(value);
      double x = 0.0;
      if ((number >> x) && number.eof()) {
        if (value.find_first_of(".e") == std::string::npos) {
          tree[key] = static_cast<int>(x);
        } else {
          tree[key] = x;
        }
      } else {
        tree[key] = value;
      }
    }
    EXPECT_NE(line.find('#'), std::string::npos) << "key without a comment: " << line;
  }
  return tree;
}

TEST(InsAdapterOptions, ShippedConfigLoadsEveryKeyAndIsTheDefault) {
  const XmlRpc::XmlRpcValue tree = shippedConfig();
  const ParamSource src = ParamSource::fromTree(tree, "config/ins_adapter.yaml:");
  const InsAdapterOptions o = loadInsAdapterOptions(src);
  EXPECT_EQ(unknownParamWarnings(src), std::vector<std::string>{});
  EXPECT_GE(src.presentParams().size(), 10u);
  // The file documents the defaults: the same options as no file at all.
  const InsAdapterOptions d = loadInsAdapterOptions(ParamSource::fromTree({}, "none:"));
  EXPECT_EQ(o.driver_preset, d.driver_preset);
  EXPECT_EQ(o.odometry.pose_source, d.odometry.pose_source);
  EXPECT_EQ(o.odometry.max_gap_s, d.odometry.max_gap_s);
  EXPECT_EQ(o.odometry.backwards_reset_s, d.odometry.backwards_reset_s);
  EXPECT_EQ(o.covariance_defaults.linear_sigma_mps, d.covariance_defaults.linear_sigma_mps);
  EXPECT_EQ(o.covariance_defaults.angular_sigma_radps, d.covariance_defaults.angular_sigma_radps);
  EXPECT_EQ(o.child_frame, d.child_frame);
  EXPECT_EQ(o.publish_tf, d.publish_tf);
  EXPECT_EQ(o.input_queue_size, d.input_queue_size);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
