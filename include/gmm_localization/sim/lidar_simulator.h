#pragma once
// LidarSimulator: ray casting of the rig's HDL-32Es against a World along a Trajectory.
//
// Each firing uses the vehicle pose at its own time (motion distortion as in a real spinning
// sensor); points are expressed in the sensor frame at that firing. Per ray: self-filter
// (the ego body), 1-100 m range window, foliage porosity, falling snow (snowy pass), a return-
// power detection model (reflectivity x cos(incidence) / range^2) with random dropouts,
// Gaussian range noise and an intensity from material reflectivity, incidence and lane paint.
// All noise is keyed by (seed, sensor, revolution, firing, laser), so the output is identical
// for any number of threads. Calls on one simulator are serialised (it reuses scratch memory).

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "gmm_localization/sim/hdl32e.h"
#include "gmm_localization/sim/rig.h"
#include "gmm_localization/sim/trajectory.h"
#include "gmm_localization/sim/world.h"

namespace gmm_localization {
namespace sim {

struct LidarPoint {
  float x, y, z;    ///< [m] sensor frame at the firing time
  float intensity;  ///< 0..255, integer values
  float time_s;     ///< since the revolution start
  uint16_t ring;    ///< 0 = lowest beam
  uint8_t label;    ///< PointLabel
};

struct SensorRevolution {
  int sensor = 0;
  int64_t index = 0;
  double t_start = 0.0, t_end = 0.0;  ///< trajectory time [s]
  std::vector<LidarPoint> points;     ///< in firing order (time non-decreasing)
  size_t rays = 0;                    ///< rays cast
};

class LidarSimulator {
 public:
  /// `trajectory` must outlive the simulator. `threads` >= 1 ray-casting threads.
  LidarSimulator(std::shared_ptr<const World> world, const Trajectory& trajectory, RigConfig rig,
                 const Hdl32eConfig& config, uint64_t noise_seed, int threads = 2);
  ~LidarSimulator();

  const Hdl32eModel& model() const { return model_; }
  const RigConfig& rig() const { return rig_; }
  /// Start time of revolution `index` of `sensor` [s].
  double revolutionStart(int sensor, int64_t index) const;
  /// Revolution `index` of every sensor.
  std::vector<SensorRevolution> simulateCycle(int64_t index) const;
  SensorRevolution simulate(int sensor, int64_t index) const;

 private:
  struct Task;
  void trace(const Task& task) const;
  std::vector<SensorRevolution> run(const std::vector<int>& sensors, int64_t index) const;

  std::shared_ptr<const World> world_;
  const Trajectory& trajectory_;
  RigConfig rig_;
  Hdl32eModel model_;
  uint64_t seed_;
  int threads_;
  std::vector<std::vector<float>> self_range_;  // per sensor, per firing x laser: ego body hit [m]
  mutable std::mutex scratch_mutex_;            // run() calls are serialised
  mutable std::vector<std::vector<LidarPoint>> slot_scratch_;
  mutable std::vector<std::vector<uint8_t>> valid_scratch_;
};

}  // namespace sim
}  // namespace gmm_localization
