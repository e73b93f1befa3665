#include "gmm_localization/core/filter/ekf_state.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {

const char* stateName(int index) {
  static const char* const kNames[kStateSize] = {
      "x",           "y",           "z",          "roll",        "pitch",       "yaw",
      "vx",          "vy",          "vz",         "wx",          "wy",          "wz",
      "ax",          "ay",          "az",         "twist_scale", "gnss_bias_x", "gnss_bias_y",
      "gyro_bias_x", "gyro_bias_y", "gyro_bias_z"};
  return index >= 0 && index < kStateSize ? kNames[index] : "?";
}

double wrapAngle(double angle_rad) {
  if (!std::isfinite(angle_rad)) return angle_rad;
  if (angle_rad >= -M_PI && angle_rad < M_PI) return angle_rad;
  double a = std::fmod(angle_rad + M_PI, 2.0 * M_PI);
  if (a < 0.0) a += 2.0 * M_PI;
  a -= M_PI;
  return a >= M_PI ? a - 2.0 * M_PI : a;  // fmod rounding can land exactly on +pi
}

Eigen::Matrix3d rotationFromRpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d rpyFromRotation(const Eigen::Matrix3d& r) {
  // R = Rz(y) Ry(p) Rx(r): R(2,0) = -sin p, R(2,1) = cos p sin r, R(2,2) = cos p cos r,
  // R(1,0) = sin y cos p, R(0,0) = cos y cos p.
  const double pitch = -std::asin(std::clamp(r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return Eigen::Vector3d(roll, pitch, yaw);
}

Eigen::Isometry3d EkfState::pose() const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotationFromRpy(x(kStateRoll), x(kStatePitch), x(kStateYaw));
  t.translation() = x.segment<3>(kPositionBlock);
  return t;
}

void setPoseInState(const Eigen::Isometry3d& map_T_base, StateVector* x) {
  x->segment<3>(kPositionBlock) = map_T_base.translation();
  x->segment<3>(kOrientationBlock) = rpyFromRotation(map_T_base.linear());
}

}  // namespace gmm_localization
