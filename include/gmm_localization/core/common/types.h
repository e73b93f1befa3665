#pragma once
// The core's vocabulary: poses, point lists, 6 x 6 matrices and their conversions, shared by
// every stage (mapping, matching, filtering, localization policy) so that none includes another
// stage's header only for a type.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace gmm_localization {

/// x, y, z [m] and roll, pitch, yaw [rad] (intrinsic Z-Y-X: R = Rz(yaw) Ry(pitch) Rx(roll)) of
/// base_link in the map frame.
struct Pose6 {
  double x = 0, y = 0, z = 0, roll = 0, pitch = 0, yaw = 0;
};

/// Points of one scan or map piece [m], in the frame the owner documents.
using PointList = std::vector<Eigen::Vector3f>;

/// Covariances of (x, y, z, roll, pitch, yaw), the order of geometry_msgs PoseWithCovariance,
/// and of (vx, vy, vz, wx, wy, wz), the order of TwistWithCovariance.
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Rotation R = Rz(yaw) Ry(pitch) Rx(roll) and translation of a Pose6.
Eigen::Isometry3d toIsometry(const Pose6& p);
/// Inverse of toIsometry (Z-Y-X Euler angles; pitch clamped to [-pi/2, pi/2]).
Pose6 fromIsometry(const Eigen::Isometry3d& T);

/// The (x, y, yaw) block of a 6 x 6 pose covariance (rows and columns 0, 1 and 5): the planar
/// covariance the search and the prior tracker work with.
Eigen::Matrix3d planarCovariance(const Matrix6d& pose_covariance);

/// The cross-product matrix [v]x: skewSymmetric(v) * w == v.cross(w).
inline Eigen::Matrix3d skewSymmetric(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}
/// A 6 x 6 pose covariance holding `planar` in its (x, y, yaw) block and zeros elsewhere.
Matrix6d poseCovarianceFromPlanar(const Eigen::Matrix3d& planar);

}  // namespace gmm_localization
