#include "gmm_localization/core/common/types.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {

Eigen::Isometry3d toIsometry(const Pose6& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(p.pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(p.roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  return T;
}

Pose6 fromIsometry(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  Pose6 p;
  p.x = T.translation().x();
  p.y = T.translation().y();
  p.z = T.translation().z();
  // Z-Y-X Euler angles; pitch clamped away from the singularity (vehicles never get there).
  p.pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  p.roll = std::atan2(R(2, 1), R(2, 2));
  p.yaw = std::atan2(R(1, 0), R(0, 0));
  return p;
}

namespace {
constexpr int kPlanarIndex[3] = {0, 1, 5};  // x, y, yaw in (x, y, z, roll, pitch, yaw)
}  // namespace

Eigen::Matrix3d planarCovariance(const Matrix6d& c) {
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out(i, j) = c(kPlanarIndex[i], kPlanarIndex[j]);
  }
  return out;
}

Matrix6d poseCovarianceFromPlanar(const Eigen::Matrix3d& planar) {
  Matrix6d c = Matrix6d::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c(kPlanarIndex[i], kPlanarIndex[j]) = planar(i, j);
  }
  return c;
}

}  // namespace gmm_localization
