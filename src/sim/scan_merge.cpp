#include "gmm_localization/sim/scan_merge.h"

#include "firing_poses.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gmm_localization {
namespace sim {

MergedScan mergeRevolutions(const std::vector<SensorRevolution>& revolutions,
                            const RigConfig& rig) {
  MergedScan out;
  out.stamp = std::numeric_limits<double>::infinity();
  out.complete = -std::numeric_limits<double>::infinity();
  size_t total = 0;
  for (const SensorRevolution& r : revolutions) {
    out.stamp = std::min(out.stamp, r.t_start);
    out.complete = std::max(out.complete, r.t_end);
    out.index = r.index;
    total += r.points.size();
  }
  out.points.reserve(total);
  for (const SensorRevolution& r : revolutions) {
    const Eigen::Isometry3f t = rig.sensors[r.sensor].base_to_sensor.cast<float>();
    const float dt = static_cast<float>(r.t_start - out.stamp);
    for (const LidarPoint& p : r.points) {
      const Eigen::Vector3f q = t * Eigen::Vector3f(p.x, p.y, p.z);
      out.points.push_back({q.x(), q.y(), q.z(), p.intensity, p.time_s + dt, p.ring, p.label});
    }
  }
  return out;
}

std::vector<LidarPoint> deskewToStamp(const std::vector<SensorRevolution>& revolutions,
                                      const RigConfig& rig, const Hdl32eModel& model,
                                      const Trajectory& trajectory, double stamp) {
  std::vector<LidarPoint> out;
  size_t total = 0;
  for (const SensorRevolution& r : revolutions) total += r.points.size();
  out.reserve(total);
  const Eigen::Isometry3d map_to_base = trajectory.pose(stamp).inverse();
  for (const SensorRevolution& r : revolutions) {
    FiringPoses poses(trajectory, rig.sensors[r.sensor].base_to_sensor, r.t_start,
                      model.firingPeriod());
    int cached_firing = -1;
    Eigen::Isometry3f t_stamp_sensor = Eigen::Isometry3f::Identity();
    for (const LidarPoint& p : r.points) {
      // Recover the firing from the point time and its laser's offset within the firing cycle.
      const int laser = p.ring < 16 ? 2 * p.ring : 2 * (p.ring - 16) + 1;
      const int firing = static_cast<int>(
          std::lround((p.time_s - laser * Hdl32eModel::kLaserIntervalS) / model.firingPeriod()));
      if (firing != cached_firing) {
        t_stamp_sensor = (map_to_base * poses.at(firing)).cast<float>();
        cached_firing = firing;
      }
      const Eigen::Vector3f q = t_stamp_sensor * Eigen::Vector3f(p.x, p.y, p.z);
      out.push_back({q.x(), q.y(), q.z(), p.intensity,
                     static_cast<float>(r.t_start - stamp) + p.time_s, p.ring, p.label});
    }
  }
  return out;
}

}  // namespace sim
}  // namespace gmm_localization
