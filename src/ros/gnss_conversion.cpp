#include "gmm_localization/ros/gnss_conversion.h"

#include <cmath>

namespace gmm_localization {
namespace node {

GnssFix gnssFixFromMsg(const sensor_msgs::NavSatFix& msg) {
  GnssFix f;
  f.stamp_s = msg.header.stamp.toSec();
  f.position = {msg.latitude, msg.longitude, msg.altitude};
  f.has_solution = msg.status.status >= sensor_msgs::NavSatStatus::STATUS_FIX;
  if (msg.position_covariance_type != sensor_msgs::NavSatFix::COVARIANCE_TYPE_UNKNOWN) {
    const auto& c = msg.position_covariance;  // ENU, row-major
    f.east_var_m2 = c[0];
    f.north_var_m2 = c[4];
    f.up_var_m2 = c[8];
    f.east_north_cov_m2 = c[1];
    if (!(std::isfinite(c[1]) && std::isfinite(c[0]) && std::isfinite(c[4]))) {
      f.east_var_m2 = f.north_var_m2 = NAN;
      f.east_north_cov_m2 = 0.0;
    }
  }
  return f;
}

Result<GnssHeading> gnssHeadingFromMsg(const sensor_msgs::Imu& msg, double imu_to_base_yaw_rad) {
  using R = Result<GnssHeading>;
  if (msg.orientation_covariance[0] == -1.0) {
    return R::failure("the Imu message carries no orientation (orientation_covariance[0] = -1)");
  }
  const auto& q = msg.orientation;
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!std::isfinite(n) || std::abs(n - 1.0) > 1e-2) {
    return R::failure("the Imu orientation is not a unit quaternion");
  }
  GnssHeading h;
  h.stamp_s = msg.header.stamp.toSec();
  // Yaw of the rotation (ZYX convention), then the mounting yaw of base_link in the Imu frame.
  // (this form of atan2 does not need the quaternion normalised).
  const double yaw_imu =
      std::atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z);
  h.enu_yaw_rad = std::remainder(yaw_imu + imu_to_base_yaw_rad, 2.0 * M_PI);
  const double var = msg.orientation_covariance[8];
  h.sigma_rad = std::isfinite(var) && var > 0.0 ? std::sqrt(var) : NAN;
  return h;
}

geometry_msgs::PoseWithCovarianceStamped initialPoseMsg(const GnssPoseEstimate& e,
                                                        const std::string& map_frame) {
  geometry_msgs::PoseWithCovarianceStamped m;
  m.header.frame_id = map_frame;
  m.header.stamp.fromSec(e.stamp_s);
  m.pose.pose.position.x = e.x_m;
  m.pose.pose.position.y = e.y_m;
  m.pose.pose.position.z = e.z_m;
  m.pose.pose.orientation.w = std::cos(0.5 * e.yaw_rad);
  m.pose.pose.orientation.z = std::sin(0.5 * e.yaw_rad);
  auto& c = m.pose.covariance;  // x y z roll pitch yaw, row-major
  const int idx[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c[idx[r] * 6 + idx[k]] = e.cov_xy_yaw(r, k);
  }
  const double z_sigma = std::isfinite(e.z_sigma_m) ? e.z_sigma_m : 10.0;
  c[2 * 6 + 2] = z_sigma * z_sigma;
  c[3 * 6 + 3] = c[4 * 6 + 4] = 0.01;
  return m;
}

}  // namespace node
}  // namespace gmm_localization
