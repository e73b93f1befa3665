#pragma once
// INS driver conventions -> base_link, and the dead reckoning of odom -> base_link: the maths of
// the INS adapter (ros/ins_adapter.h), ROS-free.
//
// The EKF and the matcher's deskewing read the twist of nav_msgs/Odometry in base_link (REP-105:
// the twist is in child_frame_id). Real INS drivers do not do that: Applanix drivers publish the
// velocity in the world frame (ENU or NED), the body quantities in the Applanix vehicle frame
// (FRD) and the solution at the INS reference point, not at base_link. These functions turn
// one such report into the twist of base_link in base_link axes and the pose of base_link.
//
// Frames. World: ENU (x east, y north, z up; REP-103) or NED (x north, y east, z down).
// Body (the driver's child frame: the point and axes its solution is given for): FLU (x forward,
// y left, z up; REP-103) or FRD (x forward, y right, z down; Applanix's vehicle frame). In TF the
// child frame has REP-103 axes; FRD quantities are those axes with y and z negated. Internally
// everything is converted to an ENU world and FLU bodies.
//
// Chain for one report (all exact, no small-angle approximation):
//   enu_R_child = the attitude read with its convention (childAttitudeEnuFlu)
//   v_child     = enu_R_child^T v_enu  (world velocity)   or the body velocity in FLU
//   w_child     = the body rates in FLU
//   [v_base; w_base] = Ad(base_T_child) [v_child; w_child]      (lever arm, twistTransform)
//     i.e. w_base = R w_child, v_base = R v_child + p x w_base   (R, p: base_T_child)
//   world_T_base = [enu_R_child, p_enu] * base_T_child^-1
// The twist covariance goes through the same linear map (the attitude's own uncertainty is not
// propagated into the rotated velocity: it is a fraction of a degree on an INS).

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/common/types.h"

namespace gmm_localization {

/// Frame of the reported linear velocity (twist.linear).
enum class InsVelocityFrame {
  kBody,  ///< the child frame, axes InsBodyAxes (REP-105)
  kEnu,   ///< world ENU: east, north, up
  kNed,   ///< world NED: north, east, down
};

/// Axes of the body quantities the driver reports: angular velocity (always body rates), a body
/// linear velocity, and the body of the attitude quaternion (kEnu / kNed attitudes).
enum class InsBodyAxes {
  kFlu,  ///< x forward, y left, z up (REP-103)
  kFrd,  ///< x forward, y right, z down (Applanix vehicle frame, aerospace)
};

/// What the reported orientation quaternion (pose.orientation) means.
enum class InsAttitude {
  kEnu,  ///< rotation ENU <- body (body axes InsBodyAxes); REP-103 with FLU
  kNed,  ///< rotation NED <- body (body axes InsBodyAxes); aerospace with FRD
  /// The quaternion tf2::Quaternion::setEuler(heading, pitch, roll) makes from the Applanix
  /// angles (rotations about Y, X and Z: tf2's setEuler is not setRPY), as Autoware's
  /// applanix_driver lvx_client publishes on its odometry. The angles are read back out of it;
  /// they give NED <- FRD (heading from north, clockwise; pitch nose up; roll right wing down).
  /// Needs InsBodyAxes::kFrd.
  kNedSetEuler,
};

/// Names used by the parameters: "body" "enu" "ned"; "flu" "frd"; "enu" "ned" "ned_set_euler".
const char* insVelocityFrameName(InsVelocityFrame f);
const char* insBodyAxesName(InsBodyAxes a);
const char* insAttitudeName(InsAttitude a);
/// Parses a name above; false (out unchanged) for any other string.
bool parseInsVelocityFrame(const std::string& name, InsVelocityFrame& out);
bool parseInsBodyAxes(const std::string& name, InsBodyAxes& out);
bool parseInsAttitude(const std::string& name, InsAttitude& out);

/// How one driver reports; the defaults are REP-105 (twist in the child frame, FLU, ENU).
struct InsConvention {
  InsVelocityFrame velocity_frame = InsVelocityFrame::kBody;
  InsBodyAxes body_axes = InsBodyAxes::kFlu;
  InsAttitude attitude = InsAttitude::kEnu;
  /// Empty when consistent; else the problem (ned_set_euler with FLU axes).
  std::string validate() const;
};

/// ENU <- NED: (n, e, d) -> (e, n, -d). Its own inverse.
Eigen::Matrix3d enuFromNed();
/// FLU <- FRD: (x, y, z) -> (x, -y, -z). Its own inverse.
Eigen::Matrix3d fluFromFrd();

/// Applanix attitude angles [rad]: heading from north, clockwise; pitch nose up; roll right wing
/// down (the vehicle frame FRD in NED).
struct ApplanixAngles {
  double roll = 0.0, pitch = 0.0, heading = 0.0;
};
/// NED <- FRD of those angles: Rz(heading) Ry(pitch) Rx(roll).
Eigen::Quaterniond nedFrdFromApplanix(const ApplanixAngles& a);
/// The quaternion tf2::Quaternion::setEuler(yaw, pitch, roll) makes: Ry(yaw) Rx(pitch) Rz(roll).
Eigen::Quaterniond setEulerQuaternion(double yaw, double pitch, double roll);
/// The angles back out of setEulerQuaternion(heading, pitch, roll): pitch in [-pi/2, pi/2],
/// heading and roll in (-pi, pi] (heading 0-360 deg comes back modulo a turn).
ApplanixAngles applanixFromSetEuler(const Eigen::Quaterniond& q);

/// ENU <- FLU attitude of the child frame from the reported (unit) quaternion.
Eigen::Quaterniond childAttitudeEnuFlu(const Eigen::Quaterniond& reported,
                                       const InsConvention& convention);

/// The twist of frame b from that of frame c on the same rigid body (each at its frame's origin,
/// in its frame's axes): [v_b; w_b] = twistTransform(b_T_c) [v_c; w_c], the adjoint
/// [[R, [p]x R], [0, R]] of b_T_c = (R, p).
Matrix6d twistTransform(const Eigen::Isometry3d& b_T_c);

/// One driver message as numbers (nav_msgs/Odometry fields), in the driver's conventions.
struct InsReport {
  double stamp_s = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< child frame, in the attitude's world
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   ///< [m/s], InsVelocityFrame
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< [rad/s], body (InsBodyAxes)
  Matrix6d pose_covariance = Matrix6d::Zero();   ///< message order (x y z roll pitch yaw)
  Matrix6d twist_covariance = Matrix6d::Zero();  ///< message order, the frames above
};

/// Sigmas for a twist covariance block the driver leaves unknown.
struct InsCovarianceDefaults {
  double linear_sigma_mps = 0.05;
  double angular_sigma_radps = 0.01;
};

/// A report moved to base_link.
struct InsBaseSample {
  double stamp_s = 0.0;
  /// base_link in the driver's world, as ENU (its origin: the driver's).
  Eigen::Isometry3d world_T_base = Eigen::Isometry3d::Identity();
  Vector6d twist = Vector6d::Zero();  ///< of base_link, in base_link: vx vy vz wx wy wz
  /// Of `twist`. A block (linear, angular) the driver left unknown (every variance <= 0: zeros,
  /// or the -1 "not provided" marker) is filled from InsCovarianceDefaults before the
  /// propagation; when both are unknown the result is all zeros (unknown: the EKF applies its
  /// own defaults).
  Matrix6d twist_covariance = Matrix6d::Zero();
  /// Of world_T_base: the position block rotated to ENU, the attitude block as reported (the
  /// lever arm's share is not added); all zeros when the report's diagonal is not positive.
  Matrix6d pose_covariance = Matrix6d::Zero();
};

/// Moves one report to base_link. base_T_child: the child frame (REP-103 axes) in base_link
/// (identity when the driver already reports for base_link). Fails, with the reason, on a
/// non-finite stamp, value or transform, or an orientation that is not a unit quaternion.
Result<InsBaseSample> insSampleInBaseLink(const InsReport& report, const InsConvention& convention,
                                          const Eigen::Isometry3d& base_T_child,
                                          const InsCovarianceDefaults& defaults = {});

/// T * Exp(twist * dt): the pose after moving for dt with the constant body twist (v, w) (exact
/// SE(3) exponential: a circle arc for constant speed and yaw rate).
Eigen::Isometry3d integrateBodyTwist(const Eigen::Isometry3d& T, const Vector6d& twist, double dt);

/// Where odom -> base_link comes from.
enum class InsPoseSource {
  /// Integrated from the base_link twist (trapezoidal, integrateBodyTwist over each interval):
  /// continuous, never jumps when the INS's GNSS corrections move its position.
  kDeadReckoning,
  /// The driver's pose moved to base_link.
  kDriver,
};
const char* insPoseSourceName(InsPoseSource s);  ///< "dead_reckoning", "driver"
bool parseInsPoseSource(const std::string& name, InsPoseSource& out);

struct InsOdometryOptions {
  InsPoseSource pose_source = InsPoseSource::kDeadReckoning;
  /// An interval longer than this is still integrated (with the mean twist) but reported as a
  /// gap [s].
  double max_gap_s = 1.0;
  /// A stamp this much older than the newest restarts the odometry (a bag looped); younger ones
  /// are dropped as out of order [s].
  double backwards_reset_s = 1.0;
  std::string validate() const;  ///< empty when valid
};

enum class InsOdometryStep {
  kStarted,            ///< the first sample: odom starts at base_link (ENU axes, position 0)
  kIntegrated,         ///< moved on by the interval since the previous sample
  kIntegratedOverGap,  ///< the same over an interval longer than max_gap_s
  kDroppedOutOfOrder,  ///< stamp not after the newest (and not a restart): pose unchanged
  kRestarted,          ///< time went back by more than backwards_reset_s: started again
};
const char* insOdometryStepName(InsOdometryStep s);

/// odom -> base_link from successive base_link samples. The odom frame is the ENU frame at
/// base_link's first position: it starts with the reported attitude and position zero. With
/// kDriver, odom_T_base is the driver's pose minus that first position.
class InsOdometry {
 public:
  explicit InsOdometry(const InsOdometryOptions& options = {});

  struct Update {
    InsOdometryStep step = InsOdometryStep::kStarted;
    Eigen::Isometry3d odom_T_base = Eigen::Isometry3d::Identity();
    double dt_s = 0.0;  ///< interval integrated (0 for a start or a drop)
  };
  /// Adds one sample (stamps must increase); returns the pose at its stamp.
  Update add(const InsBaseSample& sample);

  bool started() const { return started_; }
  const Eigen::Isometry3d& pose() const { return odom_T_base_; }
  double stamp() const { return stamp_s_; }
  void reset() { started_ = false; }

 private:
  void start(const InsBaseSample& sample);

  InsOdometryOptions options_;
  bool started_ = false;
  double stamp_s_ = 0.0;
  Vector6d twist_ = Vector6d::Zero();
  Eigen::Vector3d world_origin_ = Eigen::Vector3d::Zero();
  Eigen::Isometry3d odom_T_base_ = Eigen::Isometry3d::Identity();
};

}  // namespace gmm_localization
