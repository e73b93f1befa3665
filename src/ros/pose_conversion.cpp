#include "gmm_localization/ros/pose_conversion.h"

#include <cmath>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace node {

geometry_msgs::Pose toMsg(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose p;
  p.position.x = T.translation().x();
  p.position.y = T.translation().y();
  p.position.z = T.translation().z();
  const Eigen::Quaterniond q(T.linear());
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

Eigen::Isometry3d fromMsg(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  Eigen::Quaterniond q(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
  T.linear() = q.normalized().toRotationMatrix();
  return T;
}

Eigen::Isometry3d fromMsg(const geometry_msgs::Transform& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  T.linear() = q.normalized().toRotationMatrix();
  return T;
}

void toMsg(const Eigen::Isometry3d& T, geometry_msgs::Transform& msg) {
  const geometry_msgs::Pose p = toMsg(T);
  msg.translation.x = p.position.x;
  msg.translation.y = p.position.y;
  msg.translation.z = p.position.z;
  msg.rotation = p.orientation;
}

geometry_msgs::Pose toMsg(const Pose6& p) { return toMsg(toIsometry(p)); }

bool isFinite(const geometry_msgs::Pose& p) {
  const double q2 = p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                    p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w;
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) &&
         std::isfinite(p.position.z) && std::isfinite(q2) && q2 > 1e-6;
}

}  // namespace node
}  // namespace gmm_localization
