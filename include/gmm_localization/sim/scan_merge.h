#pragma once
// Merging the rig's revolutions into one scan in base_link, and ground-truth deskewing.
//
// Merge policy (what the cloud_merger produces): merged scan c holds revolution c of every
// sensor (sensor phases lie in [0, T), so these revolutions start within one period). Its stamp
// is the earliest revolution start; each point is transformed by its sensor's extrinsic only
// (no motion compensation) and its time is re-referenced to that stamp, so times lie in
// [0, 2T). It is complete (and published) at the latest revolution end.

#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/sim/lidar_simulator.h"
#include "gmm_localization/sim/rig.h"
#include "gmm_localization/sim/trajectory.h"

namespace gmm_localization {
namespace sim {

struct MergedScan {
  int64_t index = 0;
  double stamp = 0.0;              ///< earliest revolution start [s]
  double complete = 0.0;           ///< latest revolution end [s]
  std::vector<LidarPoint> points;  ///< base_link; time relative to stamp
};

/// `revolutions` hold one revolution per sensor (any order).
MergedScan mergeRevolutions(const std::vector<SensorRevolution>& revolutions, const RigConfig& rig);

/// Points of `revolutions` expressed in base_link at time `stamp`, each moved with the ground
/// truth pose at its own firing time (exact deskewing; what build_map needs). Times keep their
/// offset from `stamp`.
std::vector<LidarPoint> deskewToStamp(const std::vector<SensorRevolution>& revolutions,
                                      const RigConfig& rig, const Hdl32eModel& model,
                                      const Trajectory& trajectory, double stamp);

}  // namespace sim
}  // namespace gmm_localization
