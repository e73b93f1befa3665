#pragma once
// Small simulated scenes for the simulator's unit tests: a 400 m town, a short route, coarse
// azimuth steps, so each test runs in about a second.

#include <memory>

#include "gmm_localization/sim/simulation.h"

namespace gmm_localization {
namespace sim {
namespace testing {

inline TownConfig smallTown(uint64_t seed = 3) {
  TownConfig c;
  c.seed = seed;
  c.size_x_m = c.size_y_m = 400.0;
  c.block_min_m = 90.0;
  c.block_max_m = 120.0;
  return c;
}

/// A config for a short segment of `type` in the small town: coarse azimuth step (8 x 0.166
/// deg), one INS/GT stream, a few seconds of driving.
inline SimulationConfig shortSegment(PassType type, double duration_s = 1.0,
                                     uint64_t pass_seed = 1) {
  SimulationConfig c = SimulationConfig::defaults(type, pass_seed);
  c.town = smallTown();
  c.route.length_m = 800.0;
  c.start_offset_m = 120.0;
  c.max_duration_s = duration_s;
  c.lidar.firing_decimation = 8;
  c.emit_revolutions = true;
  c.emit_merged = true;
  c.emit_deskewed = true;
  return c;
}

inline std::unique_ptr<Simulation> makeSimulation(const SimulationConfig& c) {
  auto sim = Simulation::create(c);
  if (!sim) return nullptr;
  return std::move(*sim);
}

}  // namespace testing
}  // namespace sim
}  // namespace gmm_localization
