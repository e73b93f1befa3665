#include "gmm_localization/ros/ekf_node_conversions.h"

#include <cmath>

#include <tf2_eigen/tf2_eigen.h>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/ros/pose_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

Eigen::Matrix3d matrix3(const boost::array<double, 9>& c) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m(i, j) = c[i * 3 + j];
  }
  return m;
}

Eigen::Vector3d vec(const geometry_msgs::Vector3& v) { return {v.x, v.y, v.z}; }

void setVec(const Eigen::Vector3d& v, geometry_msgs::Vector3& out) {
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
}

}  // namespace

Matrix6d covarianceFromMsg(const boost::array<double, 36>& c) {
  Matrix6d m;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) m(i, j) = c[i * 6 + j];
  }
  return m;
}

void covarianceToMsg(const Matrix6d& c, boost::array<double, 36>& out) {
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) out[i * 6 + j] = c(i, j);
  }
}

Result<ImuMeasurement> imuFromMsg(const sensor_msgs::Imu& msg,
                                  const Eigen::Quaterniond& base_R_imu) {
  using R = Result<ImuMeasurement>;
  ImuMeasurement m;
  m.stamp_s = msg.header.stamp.toSec();
  if (!std::isfinite(m.stamp_s)) return R::failure("IMU stamp is not finite");
  const Eigen::Matrix3d rot = base_R_imu.normalized().toRotationMatrix();
  const Eigen::Quaterniond q(msg.orientation.w, msg.orientation.x, msg.orientation.y,
                             msg.orientation.z);
  const double norm = q.norm();
  if (msg.orientation_covariance[0] != -1.0 && std::isfinite(norm) && std::abs(norm - 1.0) < 1e-3) {
    m.has_orientation = true;
    m.orientation = q.normalized() * base_R_imu.normalized().conjugate();
    m.orientation_covariance = matrix3(msg.orientation_covariance);
  }
  if (msg.angular_velocity_covariance[0] != -1.0) {
    m.has_angular_velocity = true;
    m.angular_velocity_radps = rot * vec(msg.angular_velocity);
    m.angular_velocity_covariance =
        rot * matrix3(msg.angular_velocity_covariance) * rot.transpose();
  }
  if (msg.linear_acceleration_covariance[0] != -1.0) {
    m.has_linear_acceleration = true;
    m.linear_acceleration_mps2 = rot * vec(msg.linear_acceleration);
    m.linear_acceleration_covariance =
        rot * matrix3(msg.linear_acceleration_covariance) * rot.transpose();
  }
  if (!m.has_orientation && !m.has_angular_velocity && !m.has_linear_acceleration) {
    return R::failure("IMU message provides no part (all covariance[0] == -1 or bad quaternion)");
  }
  return m;
}

TwistMeasurement twistFromOdometryMsg(const nav_msgs::Odometry& msg) {
  TwistMeasurement t;
  t.stamp_s = msg.header.stamp.toSec();
  t.linear_mps = vec(msg.twist.twist.linear);
  t.angular_radps = vec(msg.twist.twist.angular);
  t.covariance = covarianceFromMsg(msg.twist.covariance);
  return t;
}

OdometrySample odometrySampleFromMsg(const nav_msgs::Odometry& msg) {
  OdometrySample s;
  s.stamp_s = msg.header.stamp.toSec();
  s.odom_T_base = fromMsg(msg.pose.pose);
  s.linear_mps = vec(msg.twist.twist.linear);
  s.angular_radps = vec(msg.twist.twist.angular);
  return s;
}

PosteriorEstimate posteriorFromOdometryMsg(const nav_msgs::Odometry& msg) {
  PosteriorEstimate p;
  p.stamp_s = msg.header.stamp.toSec();
  p.map_T_base = fromMsg(msg.pose.pose);
  p.covariance = covarianceFromMsg(msg.pose.covariance);
  p.twist.linear_mps = vec(msg.twist.twist.linear);
  p.twist.angular_radps = vec(msg.twist.twist.angular);
  return p;
}

bool odometryMsgFromState(const EkfState& s, const std::string& map_frame,
                          const std::string& base_frame, nav_msgs::Odometry& msg) {
  if (!s.x.allFinite() || !s.P.allFinite()) return false;
  msg.header.frame_id = map_frame;
  msg.child_frame_id = base_frame;
  msg.pose.pose = node::toMsg(s.pose());
  covarianceToMsg(s.poseCovariance(), msg.pose.covariance);
  setVec(s.linearVelocity(), msg.twist.twist.linear);
  setVec(s.angularVelocity(), msg.twist.twist.angular);
  covarianceToMsg(s.twistCovariance(), msg.twist.covariance);
  return isFinite(msg.pose.pose);
}

Result<PoseWithCovariance6> poseFromMsg(const geometry_msgs::PoseWithCovarianceStamped& msg) {
  using R = Result<PoseWithCovariance6>;
  if (!isFinite(msg.pose.pose)) return R::failure("pose has a non-finite value or zero quaternion");
  PoseWithCovariance6 out;
  out.stamp_s = msg.header.stamp.toSec();
  out.pose = fromIsometry(fromMsg(msg.pose.pose));
  out.covariance = covarianceFromMsg(msg.pose.covariance);
  if (!out.covariance.allFinite()) return R::failure("pose covariance has a non-finite value");
  return out;
}

Result<PoseWithCovariance6> initialPoseInMap(const geometry_msgs::PoseWithCovarianceStamped& msg,
                                             const std::string& map_frame,
                                             const tf2_ros::Buffer& tf) {
  geometry_msgs::PoseWithCovarianceStamped in_map = msg;
  if (msg.header.frame_id != map_frame) {
    try {
      const auto t =
          tf.lookupTransform(map_frame, msg.header.frame_id, ros::Time(0), ros::Duration(0.1));
      in_map.pose.pose = node::toMsg(tf2::transformToEigen(t) * fromMsg(msg.pose.pose));
    } catch (const tf2::TransformException& e) {
      return Result<PoseWithCovariance6>::failure("in frame '" + msg.header.frame_id +
                                                  "': " + e.what());
    }
  }
  return poseFromMsg(in_map);
}

}  // namespace node
}  // namespace gmm_localization
