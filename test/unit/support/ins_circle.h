#pragma once
// Synthetic ground truth for the INS adapter's tests (test/unit/filter/ins_frames_test.cpp,
// test/ros/ins_adapter_test.cpp): base_link drives a circle at a constant yaw rate with a
// constant roll and pitch (a helix when pitched), its speed constant or varying; an INS whose
// reference point (the child frame, REP-103 axes) sits at base_T_child reports for that point.
// The truth comes from closed forms (velocities, rotations, the constant-speed position) or a
// fine Simpson integral (varying speed), independent of the code under test.

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace gmm_localization {
namespace test {

struct InsCircle {
  double speed0 = 10.0;               ///< [m/s] forward speed of base_link
  double speed_amplitude = 0.0;       ///< speed(t) = speed0 + amplitude sin(2 pi f t) [m/s]
  double speed_frequency = 0.25;      ///< f [Hz]
  double yaw_rate = 0.2;              ///< [rad/s] about the world vertical
  double yaw0 = 0.4;                  ///< ENU yaw at t = 0 [rad]
  double roll = -0.02, pitch = 0.03;  ///< constant tilt of base_link (Z-Y-X) [rad]
  Eigen::Vector3d p0 = Eigen::Vector3d(120.0, -45.0, 3.0);  ///< base_link at t = 0, ENU [m]
  Eigen::Isometry3d base_T_child = Eigen::Isometry3d::Identity();

  double speed(double t) const {
    return speed0 + speed_amplitude * std::sin(2.0 * M_PI * speed_frequency * t);
  }
  Eigen::Matrix3d tilt() const {
    return (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
  }
  /// enu_R_base.
  Eigen::Matrix3d rotation(double t) const {
    return Eigen::AngleAxisd(yaw0 + yaw_rate * t, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
           tilt();
  }
  /// Velocity of base_link in the world (ENU).
  Eigen::Vector3d worldVelocity(double t) const {
    return rotation(t) * Eigen::Vector3d(speed(t), 0.0, 0.0);
  }
  Eigen::Vector3d worldRates() const { return Eigen::Vector3d(0.0, 0.0, yaw_rate); }
  /// base_link's twist in base_link: (speed, 0, 0), tilt^T (0, 0, yaw rate).
  Eigen::Matrix<double, 6, 1> bodyTwist(double t) const {
    Eigen::Matrix<double, 6, 1> x;
    x << speed(t), 0.0, 0.0, tilt().transpose() * worldRates();
    return x;
  }
  Eigen::Vector3d position(double t) const {
    if (speed_amplitude == 0.0) {
      const Eigen::Vector3d a = tilt() * Eigen::Vector3d(speed0, 0.0, 0.0);
      auto F = [&](double psi) -> Eigen::Vector3d {
        return Eigen::Vector3d(std::sin(psi) * a.x() + std::cos(psi) * a.y(),
                               -std::cos(psi) * a.x() + std::sin(psi) * a.y(), 0.0) /
               yaw_rate;
      };
      Eigen::Vector3d p = p0 + F(yaw0 + yaw_rate * t) - F(yaw0);
      p.z() += a.z() * t;
      return p;
    }
    // Simpson's rule, steps <= 5 ms (error ~ h^4: far below the tolerances).
    const int n = 2 * std::max(1, static_cast<int>(std::ceil(t / 0.01)));
    const double h = t / n;
    Eigen::Vector3d sum = worldVelocity(0.0) + worldVelocity(t);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * worldVelocity(i * h);
    return p0 + sum * h / 3.0;
  }
  Eigen::Isometry3d pose(double t) const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotation(t);
    T.translation() = position(t);
    return T;
  }

  // The INS reference point (child frame).
  Eigen::Isometry3d childPose(double t) const { return pose(t) * base_T_child; }
  /// Velocity of the child frame's origin in the world (ENU): v_base + w x (R p).
  Eigen::Vector3d childWorldVelocity(double t) const {
    return worldVelocity(t) + worldRates().cross(rotation(t) * base_T_child.translation());
  }
  /// Body rates of the child frame in its (FLU) axes.
  Eigen::Vector3d childRates(double t) const {
    return (rotation(t) * base_T_child.linear()).transpose() * worldRates();
  }
};

}  // namespace test
}  // namespace gmm_localization
