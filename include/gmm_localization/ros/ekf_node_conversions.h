#pragma once
// ROS messages <-> the localization core's measurement and estimate types, in one place (the
// ekf and matcher nodelets and the offline `evaluate` tool use the same functions).
//
// Conventions: sensor_msgs/Imu covariance[0] == -1 means "this part is not provided"; an
// all-zero covariance means "unknown" and is replaced by LocalizationFilter's configured
// defaults (MeasurementDefaults). nav_msgs/Odometry: pose in header.frame_id, twist in
// child_frame_id (REP-105).

#include <string>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Imu.h>
#include <tf2_ros/buffer.h>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/filter/ekf_measurement.h"
#include "gmm_localization/core/localization/prior_tracker.h"

namespace gmm_localization {
namespace node {

/// 6x6 row-major message covariance <-> Matrix6d.
Matrix6d covarianceFromMsg(const boost::array<double, 36>& c);
void covarianceToMsg(const Matrix6d& c, boost::array<double, 36>& out);

/// An IMU sample expressed in base_link. base_R_imu rotates vectors from the IMU frame into
/// base_link (identity when the IMU reports in base_link): rates, specific force and their
/// covariances are rotated; the orientation becomes that of base_link (q * base_R_imu^-1); the
/// orientation covariance (about fixed axes) is kept. A part is absent when its covariance[0]
/// is -1 (or, for the orientation, when the quaternion is not unit-norm). Fails on a
/// non-finite stamp or when no part is present.
Result<ImuMeasurement> imuFromMsg(
    const sensor_msgs::Imu& msg,
    const Eigen::Quaterniond& base_R_imu = Eigen::Quaterniond::Identity());

/// The body twist of an odometry message (child frame assumed to be base_link). Non-finite
/// values are left for the filter to reject with a reason.
TwistMeasurement twistFromOdometryMsg(const nav_msgs::Odometry& msg);

/// INS sample for the OdometryBuffer: odom_T_base and the body twist.
OdometrySample odometrySampleFromMsg(const nav_msgs::Odometry& msg);

/// The EKF's published odometry (map frame) as the matcher's posterior.
PosteriorEstimate posteriorFromOdometryMsg(const nav_msgs::Odometry& msg);

/// The EKF state as nav_msgs/Odometry in map_frame with child base_frame: pose, body twist and
/// both covariances. Returns false (msg unspecified) when any number is not finite.
bool odometryMsgFromState(const EkfState& state, const std::string& map_frame,
                          const std::string& base_frame, nav_msgs::Odometry& msg);

/// A pose message with covariance as core Pose6 + Matrix6d. Fails on non-finite values or a
/// zero-norm quaternion.
struct PoseWithCovariance6 {
  double stamp_s = 0.0;
  Pose6 pose;
  Matrix6d covariance = Matrix6d::Zero();
};
Result<PoseWithCovariance6> poseFromMsg(const geometry_msgs::PoseWithCovarianceStamped& msg);

/// An /initialpose message (rviz "2D Pose Estimate") in map_frame: a pose in another frame is
/// moved into it with the latest TF (waiting up to 0.1 s), then converted by poseFromMsg. The
/// error says which step failed.
Result<PoseWithCovariance6> initialPoseInMap(const geometry_msgs::PoseWithCovarianceStamped& msg,
                                             const std::string& map_frame,
                                             const tf2_ros::Buffer& tf);

}  // namespace node
}  // namespace gmm_localization
