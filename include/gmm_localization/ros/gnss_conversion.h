#pragma once
// sensor_msgs -> the GNSS initial pose's inputs (core/localization/gnss_initial_pose.h), and its
// estimate -> the /initialpose message. No ROS master needed (unit-tested in test/ros).

#include <string>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/localization/gnss_initial_pose.h"

namespace gmm_localization {
namespace node {

/// The fix: position, solution flag (status >= STATUS_FIX), ENU covariance (NaN when the type is
/// COVARIANCE_TYPE_UNKNOWN or the values are unusable).
GnssFix gnssFixFromMsg(const sensor_msgs::NavSatFix& msg);

/// The ENU yaw of the Imu's orientation; fails when the message carries no orientation
/// (orientation_covariance[0] == -1, as sensor_msgs/Imu specifies) or a non-unit quaternion.
/// imu_to_base_yaw_rad: the yaw of base_link in the Imu's frame (from TF; 0 when they coincide).
Result<GnssHeading> gnssHeadingFromMsg(const sensor_msgs::Imu& msg, double imu_to_base_yaw_rad);

/// The estimate as an initial pose in map_frame: x, y, z, yaw with roll = pitch = 0; covariance
/// (x, y, yaw) from the estimate, z from z_sigma_m (10 m when unknown), roll and pitch 0.1 rad.
geometry_msgs::PoseWithCovarianceStamped initialPoseMsg(const GnssPoseEstimate& e,
                                                        const std::string& map_frame);

}  // namespace node
}  // namespace gmm_localization
