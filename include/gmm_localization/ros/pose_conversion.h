#pragma once
// Core poses <-> geometry_msgs, in one place (tf2_eigen style).

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/Transform.h>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace node {

/// Isometry <-> Pose (the quaternion is normalised on the way in).
geometry_msgs::Pose toMsg(const Eigen::Isometry3d& T);
Eigen::Isometry3d fromMsg(const geometry_msgs::Pose& p);
/// Isometry <-> Transform.
void toMsg(const Eigen::Isometry3d& T, geometry_msgs::Transform& msg);
Eigen::Isometry3d fromMsg(const geometry_msgs::Transform& t);
/// Pose6 (core/common/types.h) <-> Pose.
geometry_msgs::Pose toMsg(const Pose6& p);
/// True when every number in the pose (and quaternion norm) is finite and sane.
bool isFinite(const geometry_msgs::Pose& p);

}  // namespace node
}  // namespace gmm_localization
