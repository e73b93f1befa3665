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

namespace {

/// The isometry of translation t (a geometry_msgs Point or Vector3) and rotation q (normalized).
template <class Translation>
Eigen::Isometry3d isometryOf(const Translation& t, const geometry_msgs::Quaternion& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(t.x, t.y, t.z);
  T.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  return T;
}

}  // namespace

Eigen::Isometry3d fromMsg(const geometry_msgs::Pose& p) {
  return isometryOf(p.position, p.orientation);
}

Eigen::Isometry3d fromMsg(const geometry_msgs::Transform& t) {
  return isometryOf(t.translation, t.rotation);
}

void toMsg(const Eigen::Isometry3d& T, geometry_msgs::Transform& msg) {
  const geometry_msgs::Pose p = node::toMsg(T);
  msg.translation.x = p.position.x;
  msg.translation.y = p.position.y;
  msg.translation.z = p.position.z;
  msg.rotation = p.orientation;
}

geometry_msgs::Pose toMsg(const Pose6& p) { return node::toMsg(toIsometry(p)); }

bool isFinite(const geometry_msgs::Pose& p) {
  const double q2 = p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                    p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w;
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) &&
         std::isfinite(p.position.z) && std::isfinite(q2) && q2 > 1e-6;
}

}  // namespace node
}  // namespace gmm_localization
