#pragma once
// Core poses <-> geometry_msgs, in one place (tf2_eigen style).

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/Transform.h>
#include <Eigen/Geometry>

#include "gmm_localization/core/matching/search_problem.h"

namespace gmm_localization {
namespace node {

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T);
Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& p);
Eigen::Isometry3d fromTransformMsg(const geometry_msgs::Transform& t);
geometry_msgs::Transform toTransformMsg(const Eigen::Isometry3d& T);
Pose6 toPose6(const Eigen::Isometry3d& T);
Eigen::Isometry3d fromPose6(const Pose6& p);
/// True when every number in the pose (and quaternion norm) is finite and sane.
bool isFinite(const geometry_msgs::Pose& p);

}  // namespace node
}  // namespace gmm_localization
