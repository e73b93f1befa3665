#pragma once
// Private: sensor poses at firing times, from exact trajectory poses at knots every 16 firings
// (0.74 ms at full rate) with linear / normalised-quaternion interpolation between them. The
// error is far below a micrometre (the trajectory is smooth), and it saves evaluating the
// terrain under four wheels for every firing. The LIDAR simulator and the deskewing both use
// this, so deskewing undoes exactly the motion that was simulated.

#include <Eigen/Geometry>

#include "gmm_localization/sim/trajectory.h"

namespace gmm_localization {
namespace sim {

class FiringPoses {
 public:
  static constexpr int kKnotFirings = 16;
  FiringPoses(const Trajectory& trajectory, const Eigen::Isometry3d& base_to_sensor, double t_start,
              double firing_period)
      : traj_(trajectory), mount_(base_to_sensor), t_start_(t_start), period_(firing_period) {}

  /// Sensor -> map at firing f of the revolution.
  Eigen::Isometry3d at(int firing) {
    const int knot = firing / kKnotFirings;
    if (knot != knot_) {
      knot_ = knot;
      const Eigen::Isometry3d a = exact(knot * kKnotFirings), b = exact((knot + 1) * kKnotFirings);
      ta_ = a.translation();
      tb_ = b.translation();
      qa_ = Eigen::Quaterniond(a.linear());
      qb_ = Eigen::Quaterniond(b.linear());
      if (qa_.dot(qb_) < 0.0) qb_.coeffs() = -qb_.coeffs();
    }
    const double u = static_cast<double>(firing - knot * kKnotFirings) / kKnotFirings;
    Eigen::Quaterniond q;
    q.coeffs() = (1.0 - u) * qa_.coeffs() + u * qb_.coeffs();
    q.normalize();
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    out.linear() = q.toRotationMatrix();
    out.translation() = ta_ + u * (tb_ - ta_);
    return out;
  }

 private:
  Eigen::Isometry3d exact(int firing) const {
    return traj_.pose(t_start_ + firing * period_) * mount_;
  }
  const Trajectory& traj_;
  Eigen::Isometry3d mount_;
  double t_start_, period_;
  int knot_ = -1;
  Eigen::Vector3d ta_, tb_;
  Eigen::Quaterniond qa_, qb_;
};

}  // namespace sim
}  // namespace gmm_localization
