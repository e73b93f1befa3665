#include "gmm_localization/core/filter/ins_frames.h"

#include <algorithm>
#include <cmath>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {
namespace {

/// A covariance block the driver left unknown: no positive variance on its diagonal.
bool blockUnknown(const Eigen::Matrix3d& block) { return !(block.diagonal().array() > 0.0).any(); }

}  // namespace

const char* insVelocityFrameName(InsVelocityFrame f) {
  switch (f) {
    case InsVelocityFrame::kBody:
      return "body";
    case InsVelocityFrame::kEnu:
      return "enu";
    case InsVelocityFrame::kNed:
      return "ned";
  }
  return "?";
}

const char* insBodyAxesName(InsBodyAxes a) { return a == InsBodyAxes::kFlu ? "flu" : "frd"; }

const char* insAttitudeName(InsAttitude a) {
  switch (a) {
    case InsAttitude::kEnu:
      return "enu";
    case InsAttitude::kNed:
      return "ned";
    case InsAttitude::kNedSetEuler:
      return "ned_set_euler";
  }
  return "?";
}

bool parseInsVelocityFrame(const std::string& name, InsVelocityFrame& out) {
  for (InsVelocityFrame f :
       {InsVelocityFrame::kBody, InsVelocityFrame::kEnu, InsVelocityFrame::kNed}) {
    if (name == insVelocityFrameName(f)) {
      out = f;
      return true;
    }
  }
  return false;
}

bool parseInsBodyAxes(const std::string& name, InsBodyAxes& out) {
  for (InsBodyAxes a : {InsBodyAxes::kFlu, InsBodyAxes::kFrd}) {
    if (name == insBodyAxesName(a)) {
      out = a;
      return true;
    }
  }
  return false;
}

bool parseInsAttitude(const std::string& name, InsAttitude& out) {
  for (InsAttitude a : {InsAttitude::kEnu, InsAttitude::kNed, InsAttitude::kNedSetEuler}) {
    if (name == insAttitudeName(a)) {
      out = a;
      return true;
    }
  }
  return false;
}

std::string InsConvention::validate() const {
  if (attitude == InsAttitude::kNedSetEuler && body_axes != InsBodyAxes::kFrd) {
    return "attitude ned_set_euler gives the Applanix (FRD) vehicle frame: body_axes must be frd";
  }
  return "";
}

Eigen::Matrix3d enuFromNed() {
  Eigen::Matrix3d m;
  m << 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0;
  return m;
}

Eigen::Matrix3d fluFromFrd() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

Eigen::Quaterniond nedFrdFromApplanix(const ApplanixAngles& a) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(a.heading, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(a.pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(a.roll, Eigen::Vector3d::UnitX()));
}

Eigen::Quaterniond setEulerQuaternion(double yaw, double pitch, double roll) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()));
}

ApplanixAngles applanixFromSetEuler(const Eigen::Quaterniond& q) {
  // R = Ry(h) Rx(p) Rz(r): R(1,2) = -sin p, R(0,2) = sin h cos p, R(2,2) = cos h cos p,
  // R(1,0) = cos p sin r, R(1,1) = cos p cos r.
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  ApplanixAngles a;
  a.pitch = std::asin(std::max(-1.0, std::min(1.0, -R(1, 2))));
  a.heading = std::atan2(R(0, 2), R(2, 2));
  a.roll = std::atan2(R(1, 0), R(1, 1));
  return a;
}

Eigen::Quaterniond childAttitudeEnuFlu(const Eigen::Quaterniond& reported,
                                       const InsConvention& convention) {
  const Eigen::Matrix3d body_from_flu =
      convention.body_axes == InsBodyAxes::kFrd ? fluFromFrd() : Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d q = reported.normalized().toRotationMatrix();
  Eigen::Matrix3d enu_R_flu = q;
  switch (convention.attitude) {
    case InsAttitude::kEnu:
      enu_R_flu = q * body_from_flu;
      break;
    case InsAttitude::kNed:
      enu_R_flu = enuFromNed() * q * body_from_flu;
      break;
    case InsAttitude::kNedSetEuler:
      enu_R_flu = enuFromNed() *
                  nedFrdFromApplanix(applanixFromSetEuler(reported)).toRotationMatrix() *
                  fluFromFrd();
      break;
  }
  return Eigen::Quaterniond(enu_R_flu).normalized();
}

Matrix6d twistTransform(const Eigen::Isometry3d& b_T_c) {
  const Eigen::Matrix3d R = b_T_c.linear();
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = R;
  ad.topRightCorner<3, 3>() = skewSymmetric(b_T_c.translation()) * R;
  ad.bottomRightCorner<3, 3>() = R;
  return ad;
}

Result<InsBaseSample> insSampleInBaseLink(const InsReport& report, const InsConvention& convention,
                                          const Eigen::Isometry3d& base_T_child,
                                          const InsCovarianceDefaults& defaults) {
  using R = Result<InsBaseSample>;
  if (!std::isfinite(report.stamp_s)) return R::failure("stamp is not finite");
  if (!report.position.allFinite()) return R::failure("position is not finite");
  if (!report.linear_velocity.allFinite() || !report.angular_velocity.allFinite()) {
    return R::failure("twist is not finite");
  }
  if (!report.pose_covariance.allFinite() || !report.twist_covariance.allFinite()) {
    return R::failure("covariance is not finite");
  }
  const double norm = report.orientation.norm();
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-2) {
    return R::failure("orientation is not a unit quaternion (norm " + std::to_string(norm) + ")");
  }
  if (!base_T_child.matrix().allFinite()) return R::failure("child frame transform is not finite");

  const Eigen::Matrix3d enu_R_child =
      childAttitudeEnuFlu(report.orientation, convention).toRotationMatrix();
  const Eigen::Matrix3d flu_from_body =
      convention.body_axes == InsBodyAxes::kFrd ? fluFromFrd() : Eigen::Matrix3d::Identity();
  // The reported twist -> the child frame's twist in FLU: [v_child; w_child] = C [v; w].
  Eigen::Matrix3d linear_map = flu_from_body;
  switch (convention.velocity_frame) {
    case InsVelocityFrame::kBody:
      linear_map = flu_from_body;
      break;
    case InsVelocityFrame::kEnu:
      linear_map = enu_R_child.transpose();
      break;
    case InsVelocityFrame::kNed:
      linear_map = enu_R_child.transpose() * enuFromNed();
      break;
  }
  Matrix6d C = Matrix6d::Zero();
  C.topLeftCorner<3, 3>() = linear_map;
  C.bottomRightCorner<3, 3>() = flu_from_body;
  const Matrix6d J = twistTransform(base_T_child) * C;
  Vector6d reported_twist;
  reported_twist << report.linear_velocity, report.angular_velocity;

  InsBaseSample s;
  s.stamp_s = report.stamp_s;
  s.twist = J * reported_twist;

  Matrix6d cov = report.twist_covariance;
  const bool linear_unknown = blockUnknown(cov.topLeftCorner<3, 3>());
  const bool angular_unknown = blockUnknown(cov.bottomRightCorner<3, 3>());
  if (!(linear_unknown && angular_unknown)) {
    if (linear_unknown) {
      cov.topRows<3>().setZero();
      cov.leftCols<3>().setZero();
      cov.topLeftCorner<3, 3>() =
          Eigen::Matrix3d::Identity() * defaults.linear_sigma_mps * defaults.linear_sigma_mps;
    }
    if (angular_unknown) {
      cov.bottomRows<3>().setZero();
      cov.rightCols<3>().setZero();
      cov.bottomRightCorner<3, 3>() =
          Eigen::Matrix3d::Identity() * defaults.angular_sigma_radps * defaults.angular_sigma_radps;
    }
    s.twist_covariance = J * cov * J.transpose();
    s.twist_covariance = 0.5 * (s.twist_covariance + s.twist_covariance.transpose()).eval();
  }

  const bool ned_world = convention.attitude != InsAttitude::kEnu;
  const Eigen::Vector3d enu_p_child =
      ned_world ? Eigen::Vector3d(enuFromNed() * report.position) : report.position;
  Eigen::Isometry3d world_T_child = Eigen::Isometry3d::Identity();
  world_T_child.linear() = enu_R_child;
  world_T_child.translation() = enu_p_child;
  s.world_T_base = world_T_child * base_T_child.inverse();

  if ((report.pose_covariance.diagonal().array() > 0.0).all()) {
    Matrix6d A = Matrix6d::Identity();
    if (ned_world) A.topLeftCorner<3, 3>() = enuFromNed();
    s.pose_covariance = A * report.pose_covariance * A.transpose();
  }
  return s;
}

Eigen::Isometry3d integrateBodyTwist(const Eigen::Isometry3d& T, const Vector6d& twist, double dt) {
  const Eigen::Vector3d rho = twist.head<3>() * dt;
  const Eigen::Vector3d phi = twist.tail<3>() * dt;
  const double theta = phi.norm();
  const Eigen::Matrix3d W = skewSymmetric(phi);
  Eigen::Matrix3d V;
  Eigen::Matrix3d R;
  if (theta < 1e-6) {
    // Taylor series: the closed forms below lose their digits near zero.
    V = Eigen::Matrix3d::Identity() + 0.5 * W + W * W / 6.0;
    R = Eigen::Matrix3d::Identity() + W + 0.5 * W * W;
  } else {
    const double t2 = theta * theta;
    V = Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * W +
        (theta - std::sin(theta)) / (t2 * theta) * W * W;
    R = Eigen::AngleAxisd(theta, phi / theta).toRotationMatrix();
  }
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.linear() = R;
  step.translation() = V * rho;
  Eigen::Isometry3d out = T * step;
  // Re-orthonormalise: thousands of steps must not let the rotation drift from SO(3).
  out.linear() = Eigen::Quaterniond(out.linear()).normalized().toRotationMatrix();
  return out;
}

const char* insPoseSourceName(InsPoseSource s) {
  return s == InsPoseSource::kDeadReckoning ? "dead_reckoning" : "driver";
}

bool parseInsPoseSource(const std::string& name, InsPoseSource& out) {
  for (InsPoseSource s : {InsPoseSource::kDeadReckoning, InsPoseSource::kDriver}) {
    if (name == insPoseSourceName(s)) {
      out = s;
      return true;
    }
  }
  return false;
}

std::string InsOdometryOptions::validate() const {
  if (!(max_gap_s > 0.0 && std::isfinite(max_gap_s))) return "max_gap_s must be > 0";
  if (!(backwards_reset_s > 0.0 && std::isfinite(backwards_reset_s))) {
    return "backwards_reset_s must be > 0";
  }
  return "";
}

const char* insOdometryStepName(InsOdometryStep s) {
  switch (s) {
    case InsOdometryStep::kStarted:
      return "started";
    case InsOdometryStep::kIntegrated:
      return "integrated";
    case InsOdometryStep::kIntegratedOverGap:
      return "integrated over a gap";
    case InsOdometryStep::kDroppedOutOfOrder:
      return "dropped (out of order)";
    case InsOdometryStep::kRestarted:
      return "restarted (time went backwards)";
  }
  return "?";
}

InsOdometry::InsOdometry(const InsOdometryOptions& options) : options_(options) {}

void InsOdometry::start(const InsBaseSample& sample) {
  started_ = true;
  stamp_s_ = sample.stamp_s;
  twist_ = sample.twist;
  world_origin_ = sample.world_T_base.translation();
  odom_T_base_ = sample.world_T_base;
  odom_T_base_.translation().setZero();
}

InsOdometry::Update InsOdometry::add(const InsBaseSample& sample) {
  Update u;
  if (!started_) {
    start(sample);
    u.step = InsOdometryStep::kStarted;
    u.odom_T_base = odom_T_base_;
    return u;
  }
  const double dt = sample.stamp_s - stamp_s_;
  if (dt <= 0.0) {
    if (-dt > options_.backwards_reset_s) {
      start(sample);
      u.step = InsOdometryStep::kRestarted;
    } else {
      u.step = InsOdometryStep::kDroppedOutOfOrder;
    }
    u.odom_T_base = odom_T_base_;
    return u;
  }
  if (options_.pose_source == InsPoseSource::kDeadReckoning) {
    odom_T_base_ = integrateBodyTwist(odom_T_base_, 0.5 * (twist_ + sample.twist), dt);
  } else {
    odom_T_base_ = sample.world_T_base;
    odom_T_base_.translation() -= world_origin_;
  }
  stamp_s_ = sample.stamp_s;
  twist_ = sample.twist;
  u.step =
      dt > options_.max_gap_s ? InsOdometryStep::kIntegratedOverGap : InsOdometryStep::kIntegrated;
  u.dt_s = dt;
  u.odom_T_base = odom_T_base_;
  return u;
}

}  // namespace gmm_localization
