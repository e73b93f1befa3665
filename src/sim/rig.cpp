#include "gmm_localization/sim/rig.h"

#include <cmath>
#include <sstream>

#include "gmm_localization/sim/random.h"

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

/// A direction uniform on the unit sphere (normalised isotropic Gaussian vector).
Eigen::Vector3d randomDirection(Rng& rng) {
  Eigen::Vector3d v;
  do {
    v = Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
  } while (v.norm() < 1e-9);
  return v.normalized();
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

Result<ExtrinsicErrorMode> parseExtrinsicErrorMode(const std::string& name) {
  if (name == "none") return ExtrinsicErrorMode::kNone;
  if (name == "realistic") return ExtrinsicErrorMode::kRealistic;
  return Result<ExtrinsicErrorMode>::failure("unknown extrinsic error mode '" + name +
                                             "' (none or realistic)");
}

Status ExtrinsicErrorConfig::validate() const {
  std::ostringstream os;
  if (!(translation_min_m >= 0.0 && translation_max_m >= translation_min_m &&
        translation_max_m <= 0.5))
    os << "translation range [" << translation_min_m << ", " << translation_max_m
       << "] m is not an interval within [0, 0.5]";
  else if (!(rotation_min_deg >= 0.0 && rotation_max_deg >= rotation_min_deg &&
             rotation_max_deg <= 10.0))
    os << "rotation range [" << rotation_min_deg << ", " << rotation_max_deg
       << "] deg is not an interval within [0, 10]";
  if (os.str().empty()) return Status::success();
  return Status::failure("ExtrinsicErrorConfig." + os.str());
}

RigConfig perturbedRig(const RigConfig& nominal, const ExtrinsicErrorConfig& config) {
  if (config.mode == ExtrinsicErrorMode::kNone) return nominal;
  RigConfig rig = nominal;
  for (size_t k = 0; k < rig.sensors.size(); ++k) {
    // Independent streams per sensor and per component: adding a sensor or changing the
    // rotation band leaves the other draws as they were.
    Rng t_rng(hashKeys(config.seed, k, 0xE7ull));
    Rng r_rng(hashKeys(config.seed, k, 0xE8ull));
    const Eigen::Vector3d dt =
        randomDirection(t_rng) * t_rng.uniform(config.translation_min_m, config.translation_max_m);
    const double angle =
        r_rng.uniform(config.rotation_min_deg, config.rotation_max_deg) * M_PI / 180.0;
    const Eigen::Vector3d axis = randomDirection(r_rng);
    Eigen::Isometry3d& t = rig.sensors[k].base_to_sensor;
    t.linear() = Eigen::AngleAxisd(angle, axis).toRotationMatrix() * t.linear();
    t.translation() += dt;
  }
  return rig;
}

MountError mountError(const SensorMount& nominal, const SensorMount& truth) {
  MountError e;
  e.translation_m = truth.base_to_sensor.translation() - nominal.base_to_sensor.translation();
  const Eigen::AngleAxisd aa(truth.base_to_sensor.linear() *
                             nominal.base_to_sensor.linear().transpose());
  e.rotation_rad = aa.axis() * aa.angle();
  return e;
}

}  // namespace sim
}  // namespace gmm_localization
