// ROS message <-> core conversions of the ekf and matcher nodelets: IMU parts and frames,
// odometry twist and INS samples, the EKF state as odometry (round trip through the matcher's
// posterior), pose messages, and the matcher's option loaders' defaults (no master: defaults).
#include "gmm_localization/ros/ekf_node_conversions.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

sensor_msgs::Imu levelImu() {
  sensor_msgs::Imu m;
  m.header.stamp = ros::Time(100, 5000000);
  m.orientation.w = 1.0;
  m.angular_velocity.z = 0.2;
  m.linear_acceleration.x = 1.0;
  m.linear_acceleration.z = 9.81;
  m.angular_velocity_covariance[0] = m.angular_velocity_covariance[4] =
      m.angular_velocity_covariance[8] = 1e-4;
  return m;
}

TEST(ImuFromMsg, PartsFlagsCovariancesAndFrames) {
  sensor_msgs::Imu msg = levelImu();
  auto imu = imuFromMsg(msg);
  ASSERT_TRUE(imu.ok()) << imu.error();
  EXPECT_NEAR(imu->stamp_s, 100.005, 1e-9);
  EXPECT_TRUE(imu->has_orientation && imu->has_angular_velocity && imu->has_linear_acceleration);
  EXPECT_NEAR(imu->angular_velocity_radps.z(), 0.2, 1e-12);
  EXPECT_NEAR(imu->angular_velocity_covariance(1, 1), 1e-4, 1e-15);
  // All-zero covariance stays zero: LocalizationFilter applies its defaults.
  EXPECT_TRUE(imu->linear_acceleration_covariance.isZero());

  // covariance[0] == -1: the part is absent.
  msg.orientation_covariance[0] = -1.0;
  msg.linear_acceleration_covariance[0] = -1.0;
  imu = imuFromMsg(msg);
  ASSERT_TRUE(imu.ok());
  EXPECT_FALSE(imu->has_orientation);
  EXPECT_TRUE(imu->has_angular_velocity);
  EXPECT_FALSE(imu->has_linear_acceleration);
  msg.angular_velocity_covariance[0] = -1.0;
  EXPECT_FALSE(imuFromMsg(msg).ok());

  // A zero quaternion is no orientation.
  msg = levelImu();
  msg.orientation.w = 0.0;
  imu = imuFromMsg(msg);
  ASSERT_TRUE(imu.ok());
  EXPECT_FALSE(imu->has_orientation);

  // An IMU mounted yawed by +90 deg in base_link: its x axis is base_link's y.
  msg = levelImu();
  const Eigen::Quaterniond base_R_imu(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  imu = imuFromMsg(msg, base_R_imu);
  ASSERT_TRUE(imu.ok());
  EXPECT_NEAR(imu->linear_acceleration_mps2.x(), 0.0, 1e-12);
  EXPECT_NEAR(imu->linear_acceleration_mps2.y(), 1.0, 1e-12);
  EXPECT_NEAR(imu->linear_acceleration_mps2.z(), 9.81, 1e-12);
  // The sensor reports "level, yaw 0": base_link is then at yaw -90 deg.
  const Eigen::Vector3d rpy = rpyFromRotation(imu->orientation.toRotationMatrix());
  EXPECT_NEAR(rpy.z(), -M_PI / 2, 1e-9);
  EXPECT_NEAR(rpy.x(), 0.0, 1e-9);
  // Rates rotate with their covariance.
  msg.angular_velocity_covariance[0] = 4e-4;  // x variance larger
  imu = imuFromMsg(msg, base_R_imu);
  EXPECT_NEAR(imu->angular_velocity_covariance(1, 1), 4e-4, 1e-15);
  EXPECT_NEAR(imu->angular_velocity_covariance(0, 0), 1e-4, 1e-15);
}

nav_msgs::Odometry odometry() {
  nav_msgs::Odometry m;
  m.header.stamp = ros::Time(50.0);
  m.header.frame_id = "odom";
  m.child_frame_id = "base_link";
  m.pose.pose.position.x = 3.0;
  m.pose.pose.orientation.z = std::sin(0.25);
  m.pose.pose.orientation.w = std::cos(0.25);  // yaw 0.5
  m.twist.twist.linear.x = 7.0;
  m.twist.twist.angular.z = 0.1;
  for (int i = 0; i < 6; ++i) m.twist.covariance[i * 7] = 0.01 * (i + 1);
  return m;
}

TEST(OdometryConversions, TwistSampleAndPosterior) {
  const nav_msgs::Odometry m = odometry();
  const TwistMeasurement t = twistFromOdometryMsg(m);
  EXPECT_DOUBLE_EQ(t.stamp_s, 50.0);
  EXPECT_DOUBLE_EQ(t.linear_mps.x(), 7.0);
  EXPECT_DOUBLE_EQ(t.angular_radps.z(), 0.1);
  EXPECT_DOUBLE_EQ(t.covariance(5, 5), 0.06);
  const OdometrySample s = odometrySampleFromMsg(m);
  EXPECT_NEAR(s.odom_T_base.translation().x(), 3.0, 1e-12);
  EXPECT_NEAR(fromIsometry(s.odom_T_base).yaw, 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(s.linear_mps.x(), 7.0);
}

TEST(OdometryConversions, EkfStateRoundTripsThroughTheMatchersPosterior) {
  EkfState state;
  state.time_s = 12.5;
  setPoseInState(toIsometry(Pose6{1.0, 2.0, 0.5, 0.01, -0.02, 1.2}), &state.x);
  state.x(kStateVx) = 4.0;
  state.x(kStateWz) = 0.3;
  state.P = StateCovariance::Identity() * 0.04;
  state.P(kStateX, kStateY) = state.P(kStateY, kStateX) = 0.01;
  nav_msgs::Odometry msg;
  ASSERT_TRUE(odometryMsgFromState(state, "map", "base_link", msg));
  EXPECT_EQ(msg.header.frame_id, "map");
  EXPECT_EQ(msg.child_frame_id, "base_link");
  msg.header.stamp.fromSec(state.time_s);
  const PosteriorEstimate p = posteriorFromOdometryMsg(msg);
  EXPECT_NEAR(p.stamp_s, 12.5, 1e-9);
  const Pose6 back = fromIsometry(p.map_T_base);
  EXPECT_NEAR(back.y, 2.0, 1e-12);
  EXPECT_NEAR(back.pitch, -0.02, 1e-12);
  EXPECT_NEAR(back.yaw, 1.2, 1e-12);
  EXPECT_DOUBLE_EQ(p.covariance(kStateX, kStateY), 0.01);
  EXPECT_DOUBLE_EQ(p.twist.linear_mps.x(), 4.0);
  EXPECT_DOUBLE_EQ(p.twist.angular_radps.z(), 0.3);
  EXPECT_DOUBLE_EQ(msg.twist.covariance[0], 0.04);

  state.x(kStateX) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(odometryMsgFromState(state, "map", "base_link", msg));
}

TEST(PoseFromMsg, ValuesAndFailures) {
  geometry_msgs::PoseWithCovarianceStamped m;
  m.header.stamp = ros::Time(7.0);
  m.pose.pose = toMsg(toIsometry(Pose6{5.0, -1.0, 0.0, 0.0, 0.0, -0.7}));
  m.pose.covariance[0] = 0.25;
  m.pose.covariance[35] = 0.07;
  auto p = poseFromMsg(m);
  ASSERT_TRUE(p.ok()) << p.error();
  EXPECT_DOUBLE_EQ(p->stamp_s, 7.0);
  EXPECT_NEAR(p->pose.yaw, -0.7, 1e-12);
  EXPECT_DOUBLE_EQ(p->covariance(kStateYaw, kStateYaw), 0.07);
  m.pose.covariance[7] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(poseFromMsg(m).ok());
  m.pose.covariance[7] = 0.0;
  m.pose.pose.orientation = geometry_msgs::Quaternion();
  m.pose.pose.orientation.w = 0.0;
  EXPECT_FALSE(poseFromMsg(m).ok());
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
