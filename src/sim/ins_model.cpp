#include "gmm_localization/sim/ins_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace gmm_localization {
namespace sim {
namespace {

Eigen::Matrix3d smallRotation(const Eigen::Vector3d& v) {
  const double a = v.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, v / a).toRotationMatrix();
}

}  // namespace

Status InsConfig::validate() const {
  std::ostringstream os;
  if (!(odom_rate_hz >= 1.0 && odom_rate_hz <= 1000.0))
    os << "odom_rate_hz = " << odom_rate_hz << " is outside [1, 1000]";
  else if (!(imu_rate_hz >= 1.0 && imu_rate_hz <= 2000.0))
    os << "imu_rate_hz = " << imu_rate_hz << " is outside [1, 2000]";
  else if (!(std::abs(scale_error) <= 0.1))
    os << "scale_error = " << scale_error << " is outside [-0.1, 0.1]";
  else if (!(std::abs(heading_bias_rad) <= 0.2))
    os << "heading_bias_rad = " << heading_bias_rad << " is outside [-0.2, 0.2]";
  else if (!(heading_random_walk_rad_sqrt_s >= 0.0 && position_random_walk_m_sqrt_s >= 0.0 &&
             position_noise_m >= 0.0 && attitude_noise_rad >= 0.0 && velocity_noise_mps >= 0.0 &&
             gyro_noise_rad_s >= 0.0 && gyro_bias_rad_s >= 0.0 && accel_noise_mps2 >= 0.0 &&
             accel_bias_mps2 >= 0.0))
    os << "noise levels must be >= 0";
  if (os.str().empty()) return Status::success();
  return Status::failure("InsConfig." + os.str());
}

InsModel::InsModel(const Trajectory& trajectory, const InsConfig& config, double t_begin)
    : trajectory_(trajectory),
      config_(config),
      rng_(config.seed),
      t_(t_begin),
      next_odom_(t_begin),
      next_imu_(t_begin),
      t_begin_(t_begin) {
  heading_error_ = config.heading_bias_rad;
  gt_position_ = trajectory.pose(t_begin).translation();
  odom_position_ = gt_position_;
  gyro_bias_ =
      Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config.gyro_bias_rad_s;
  accel_bias_ =
      Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config.accel_bias_mps2;
}

void InsModel::integrate(double t) {
  const double dt = t - t_;
  if (dt <= 0.0) return;
  const Eigen::Vector3d p = trajectory_.pose(t).translation();
  const Eigen::Vector3d dp = p - gt_position_;
  // Start point of the odom frame = start pose: rotate increments about z by the heading error.
  const double c = std::cos(heading_error_), s = std::sin(heading_error_);
  const Eigen::Vector3d rotated(c * dp.x() - s * dp.y(), s * dp.x() + c * dp.y(), dp.z());
  const double rw = config_.position_random_walk_m_sqrt_s * std::sqrt(dt);
  odom_position_ += (1.0 + config_.scale_error) * rotated +
                    Eigen::Vector3d(rng_.normal(), rng_.normal(), 0.0) * rw;
  heading_error_ += config_.heading_random_walk_rad_sqrt_s * std::sqrt(dt) * rng_.normal();
  gt_position_ = p;
  t_ = t;
}

void InsModel::advanceTo(double t_until, std::vector<OdomSample>* odom,
                         std::vector<ImuSample>* imu) {
  const Eigen::Vector3d g(0.0, 0.0, kGravity);
  for (;;) {
    const double t = std::min(next_odom_, next_imu_);
    if (t >= t_until) break;
    integrate(t);
    const VehicleState st = trajectory_.state(t);
    const Eigen::Matrix3d rz =
        Eigen::AngleAxisd(heading_error_, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    auto noisyAttitude = [&]() {
      const Eigen::Vector3d e(rng_.normal(), rng_.normal(), rng_.normal());
      return Eigen::Matrix3d(rz * st.pose.linear() * smallRotation(e * config_.attitude_noise_rad));
    };
    if (next_odom_ <= t) {
      OdomSample o;
      o.t = t;
      o.pose.linear() = noisyAttitude();
      o.pose.translation() =
          odom_position_ +
          Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config_.position_noise_m;
      const Eigen::Vector3d v_body = st.pose.linear().transpose() * st.velocity_world;
      o.linear_velocity =
          (1.0 + config_.scale_error) * v_body +
          Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config_.velocity_noise_mps;
      o.angular_velocity =
          st.angular_velocity_body +
          Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config_.gyro_noise_rad_s;
      o.heading_error_rad = heading_error_;
      if (odom) odom->push_back(o);
      next_odom_ = t_begin_ + static_cast<double>(++odom_count_) / config_.odom_rate_hz;
    }
    if (next_imu_ <= t) {
      ImuSample m;
      m.t = t;
      m.orientation = Eigen::Quaterniond(noisyAttitude());
      m.angular_velocity =
          st.angular_velocity_body + gyro_bias_ +
          Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config_.gyro_noise_rad_s;
      m.linear_acceleration =
          st.pose.linear().transpose() * (st.acceleration_world + g) + accel_bias_ +
          Eigen::Vector3d(rng_.normal(), rng_.normal(), rng_.normal()) * config_.accel_noise_mps2;
      if (imu) imu->push_back(m);
      next_imu_ = t_begin_ + static_cast<double>(++imu_count_) / config_.imu_rate_hz;
    }
  }
}

}  // namespace sim
}  // namespace gmm_localization
