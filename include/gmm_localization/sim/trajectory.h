#pragma once
// Trajectory: the vehicle driving a Route. A speed profile along the lane path respects the
// acceleration, braking and lateral-acceleration limits and stops at some intersections; a
// small smooth lane wander varies the line between passes (faded out through turns, so the
// speed along the path stays continuous). Height, roll and pitch follow the ground under the
// four wheels (terrain slope, road crown), each wheel averaging +-0.4 m of road like a tyre and
// suspension would, so crown ridges in intersections give bumps rather than kinks.
//
// Frames: base_link is at ground level midway between the axles, x forward, y left, z up;
// poses are base_link -> map. Time t [s] runs from 0 at the start of the route. The Town and
// Route given to create() must outlive the Trajectory.

#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/route.h"
#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

struct KinematicsConfig {
  /// Varies per-road cruise speeds, stops and lane wander (use a different seed per pass).
  uint64_t seed = 11;
  double cruise_speed_mps = 13.0;  ///< nominal; per road drawn in [0.8, 1.15] x this
  double max_speed_mps = 15.0;
  double max_accel_mps2 = 1.5;
  double max_decel_mps2 = 2.0;
  double max_lateral_accel_mps2 = 2.0;
  double stop_probability = 0.3;  ///< per intersection
  double stop_min_s = 1.0, stop_max_s = 4.0;
  double lane_wander_m = 0.15;  ///< amplitude of the smooth lateral offset in the lane
  double wheelbase_m = 2.9, track_m = 1.65;
  Status validate() const;
};

/// Ground-truth state at time t.
struct VehicleState {
  double t = 0.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();           ///< base_link -> map
  Eigen::Vector3d velocity_world = Eigen::Vector3d::Zero();         ///< [m/s], map frame
  Eigen::Vector3d acceleration_world = Eigen::Vector3d::Zero();     ///< [m/s^2], map, no gravity
  Eigen::Vector3d angular_velocity_body = Eigen::Vector3d::Zero();  ///< [rad/s], base_link
  double distance_m = 0.0;                                          ///< along the route
  double speed_mps = 0.0;
};

class Trajectory {
 public:
  static Result<Trajectory> create(const Town& town, const Route& route,
                                   const KinematicsConfig& config);

  double duration() const { return t_in_.back(); }
  double length() const { return route_->length(); }
  /// Distance along the route at time t (clamped to [0, duration()]).
  double distanceAt(double t) const;
  double speedAt(double t) const;
  /// First time the vehicle reaches distance s.
  double timeAtDistance(double s) const;
  /// Pose base_link -> map at time t (clamped).
  Eigen::Isometry3d pose(double t) const;
  /// Pose plus velocities and accelerations (central differences over 5 ms).
  VehicleState state(double t) const;

 private:
  Eigen::Isometry3d poseAtDistance(double s) const;
  const Town* town_ = nullptr;
  const Route* route_ = nullptr;
  KinematicsConfig config_;
  double ds_ = 0.25;
  std::vector<double> v_, t_in_, t_out_;  // per station k at s = k * ds_
  std::vector<float> wander_gain_;        // per station: 0 in turns, 1 away from them
  double wander_phase_[2] = {0.0, 0.0};
  double wander_wavelength_[2] = {200.0, 90.0};
};

}  // namespace sim
}  // namespace gmm_localization
