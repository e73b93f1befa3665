// sensor_msgs <-> the GNSS initial pose (ros/gnss_conversion.h).
#include "gmm_localization/ros/gnss_conversion.h"

#include <cmath>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace node {
namespace {

TEST(GnssConversion, NavSatFixFields) {
  sensor_msgs::NavSatFix m;
  m.header.stamp.fromSec(12.5);
  m.latitude = 42.28;
  m.longitude = -83.74;
  m.altitude = 260.0;
  m.status.status = sensor_msgs::NavSatStatus::STATUS_FIX;
  m.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
  m.position_covariance = {4.0, 0.5, 0, 0.5, 9.0, 0, 0, 0, 16.0};
  GnssFix f = gnssFixFromMsg(m);
  EXPECT_DOUBLE_EQ(f.stamp_s, 12.5);
  EXPECT_TRUE(f.has_solution);
  EXPECT_DOUBLE_EQ(f.position.latitude_deg, 42.28);
  EXPECT_DOUBLE_EQ(f.east_var_m2, 4.0);
  EXPECT_DOUBLE_EQ(f.north_var_m2, 9.0);
  EXPECT_DOUBLE_EQ(f.up_var_m2, 16.0);
  EXPECT_DOUBLE_EQ(f.east_north_cov_m2, 0.5);

  m.status.status = sensor_msgs::NavSatStatus::STATUS_NO_FIX;
  m.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_UNKNOWN;
  f = gnssFixFromMsg(m);
  EXPECT_FALSE(f.has_solution);
  EXPECT_TRUE(std::isnan(f.east_var_m2));

  m.status.status = sensor_msgs::NavSatStatus::STATUS_GBAS_FIX;
  m.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_APPROXIMATED;
  m.position_covariance[0] = NAN;
  f = gnssFixFromMsg(m);
  EXPECT_TRUE(f.has_solution);
  EXPECT_TRUE(std::isnan(f.east_var_m2)) << "a NaN covariance counts as unknown";
}

TEST(GnssConversion, ImuHeading) {
  sensor_msgs::Imu m;
  m.header.stamp.fromSec(3.0);
  const double yaw = 2.5;
  m.orientation.w = 2.0 * std::cos(yaw / 2);  // not normalised: within 1 % only is accepted
  m.orientation.z = 2.0 * std::sin(yaw / 2);
  EXPECT_FALSE(gnssHeadingFromMsg(m, 0.0).ok());
  m.orientation.w = std::cos(yaw / 2);
  m.orientation.z = std::sin(yaw / 2);
  m.orientation_covariance[8] = 0.0004;
  auto h = gnssHeadingFromMsg(m, 0.0);
  ASSERT_TRUE(h.ok()) << h.error();
  EXPECT_NEAR(h->enu_yaw_rad, yaw, 1e-12);
  EXPECT_NEAR(h->sigma_rad, 0.02, 1e-12);
  EXPECT_DOUBLE_EQ(h->stamp_s, 3.0);
  h = gnssHeadingFromMsg(m, 1.0);  // base_link turned 1 rad from the Imu frame: wraps
  ASSERT_TRUE(h.ok());
  EXPECT_NEAR(h->enu_yaw_rad, yaw + 1.0 - 2 * M_PI, 1e-12);
  m.orientation_covariance[0] = -1.0;
  auto none = gnssHeadingFromMsg(m, 0.0);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().find("no orientation"), std::string::npos);
}

TEST(GnssConversion, InitialPoseLayout) {
  GnssPoseEstimate e;
  e.stamp_s = 7.0;
  e.x_m = 1.0;
  e.y_m = 2.0;
  e.z_m = 3.0;
  e.yaw_rad = -1.2;
  e.cov_xy_yaw << 4, 1, 0.1, 1, 5, 0.2, 0.1, 0.2, 0.01;
  const auto m = initialPoseMsg(e, "map");
  EXPECT_EQ(m.header.frame_id, "map");
  EXPECT_DOUBLE_EQ(m.header.stamp.toSec(), 7.0);
  const auto& q = m.pose.pose.orientation;
  EXPECT_NEAR(std::atan2(2 * q.w * q.z, 1 - 2 * q.z * q.z), -1.2, 1e-12);
  const auto& c = m.pose.covariance;
  EXPECT_EQ(c[0], 4);
  EXPECT_EQ(c[1], 1);
  EXPECT_EQ(c[5], 0.1);
  EXPECT_EQ(c[7], 5);
  EXPECT_EQ(c[11], 0.2);
  EXPECT_EQ(c[30], 0.1);
  EXPECT_EQ(c[31], 0.2);
  EXPECT_EQ(c[35], 0.01);
  EXPECT_EQ(c[14], 100.0) << "unknown height: 10 m";
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
