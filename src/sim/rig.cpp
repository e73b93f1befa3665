#include "gmm_localization/sim/rig.h"

#include <cmath>
#include <sstream>

namespace gmm_localization {
namespace sim {
namespace {

Eigen::Isometry3d mount(double x, double y, double z, double yaw_deg, double tilt_deg) {
  // Yaw toward the corner, then pitch about the sensor's own y axis: a positive pitch lowers its
  // +x (outward) side, so the head leans outward and sees the ground next to the car.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(tilt_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

}  // namespace

RigConfig RigConfig::fourRoofCorners(double x_m, double y_m, double z_m, double tilt_deg,
                                     double period_s) {
  RigConfig rig;
  const double phases[4] = {0.0, 0.23, 0.51, 0.74};
  const double corners[4][3] = {
      {x_m, y_m, 45.0}, {x_m, -y_m, -45.0}, {-x_m, y_m, 135.0}, {-x_m, -y_m, -135.0}};
  for (int k = 0; k < 4; ++k) {
    rig.sensors.push_back({"velodyne_" + std::to_string(k),
                           mount(corners[k][0], corners[k][1], z_m, corners[k][2], tilt_deg),
                           phases[k] * period_s});
  }
  return rig;
}

RigConfig RigConfig::single(double z_m, double tilt_deg) {
  RigConfig rig;
  rig.sensors.push_back({"velodyne_0", mount(0.0, 0.0, z_m, 0.0, tilt_deg), 0.0});
  return rig;
}

Status RigConfig::validate(double period_s) const {
  if (sensors.empty()) return Status::failure("RigConfig.sensors is empty");
  for (size_t k = 0; k < sensors.size(); ++k) {
    const SensorMount& s = sensors[k];
    if (!(s.phase_s >= 0.0 && s.phase_s < period_s)) {
      std::ostringstream os;
      os << "RigConfig.sensors[" << k << "].phase_s = " << s.phase_s << " is outside [0, "
         << period_s << ")";
      return Status::failure(os.str());
    }
    if (s.frame_id.empty())
      return Status::failure("RigConfig.sensors[" + std::to_string(k) + "].frame_id is empty");
    for (const Eigen::AlignedBox3d& b : ego_boxes) {
      if (b.contains(s.base_to_sensor.translation()))
        return Status::failure("RigConfig.sensors[" + std::to_string(k) +
                               "] sits inside an ego box");
    }
  }
  return Status::success();
}

}  // namespace sim
}  // namespace gmm_localization
