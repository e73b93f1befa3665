#pragma once
// Passes over the same town. The mapping pass is the reference whose clouds build the map;
// localization passes differ from it: `downtown` adds moving cars and pedestrians and changes
// some parked cars; `snowy` adds falling snow, a snow cover that raises and smooths the ground,
// snowbanks along the curbs, and hides lane paint. Either localization pass can also be aged
// (map_aging.h: construction sites, containers, grown trees, repaved stretches).
//
// Labels (PointLabel): 0 static structure (also unchanged parked cars and the thin snow cover,
// which is the ground surface raised by 5-15 cm, and repaved road), 1 moving actors, parked cars
// that differ from the mapping pass and map-aging objects, 2 falling snow and snowbanks.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/map_aging.h"
#include "gmm_localization/sim/town.h"
#include "gmm_localization/sim/vehicle_mesh.h"

namespace gmm_localization {
namespace sim {

enum class PassType { kMapping, kDowntown, kSnowy };

const char* passTypeName(PassType type);
/// "mapping", "downtown" or "snowy".
Result<PassType> parsePassType(const std::string& name);

struct PassConfig {
  PassType type = PassType::kMapping;
  /// Seed of what varies between passes (actors, changed cars, snow). Same type and seed gives
  /// the same pass.
  uint64_t seed = 1;
  double parked_occupancy = 0.55;        ///< share of parking slots with a car
  double parked_keep_probability = 0.6;  ///< localization passes: slots left as in mapping
  double moving_cars_per_km2 = 0.0;
  double pedestrians_per_km2 = 0.0;
  // Snow (used when snow is true).
  bool snow = false;
  double snow_depth_min_m = 0.05;
  double snow_depth_max_m = 0.15;
  double snowbank_max_height_m = 0.8;
  double snowbank_coverage = 0.7;           ///< share of curb length with a bank
  double snowfall_returns_per_ray = 0.015;  ///< probability that a ray returns from a flake
  double snowfall_mean_range_m = 4.0;       ///< flake returns: 1 m + exponential with this mean
  double snowfall_max_range_m = 15.0;
  /// What else changed since the mapping drive (localization passes only; ignored for mapping).
  /// The seed defaults to one derived from the pass type and seed.
  MapAgingConfig aging;

  /// Defaults of each pass type (mapping: no actors; downtown: 40 cars and 150 pedestrians per
  /// km^2; snowy: 25 and 60, plus snow).
  static PassConfig defaults(PassType type, uint64_t seed = 1);
  Status validate() const;
};

struct ParkedCar {
  Eigen::Vector2d center;
  double yaw_rad;
  CarShape shape;
  uint8_t label;  ///< kLabelStatic if as in the mapping pass, else kLabelDynamic
};

/// A moving car (drives a straight road line, wrapping at its end) or pedestrian (walks a
/// sidewalk back and forth).
struct Actor {
  enum class Kind { kCar, kPedestrian } kind = Kind::kCar;
  Eigen::Vector2d a, b;  ///< path ends
  double speed_mps = 1.0;
  double phase_m = 0.0;  ///< distance along the path at t = 0
  CarShape shape;
  /// Pose (actor -> map) at time t; false where the car wraps within [t0, t1] (then the actor
  /// is left out for that interval).
  bool poseAt(const Town& town, double t, Eigen::Isometry3d* pose) const;
  bool continuousOver(double t0, double t1) const;
};

/// What a pass adds to the town.
struct PassContents {
  PassConfig config;
  std::vector<ParkedCar> parked;
  std::vector<Actor> actors;
};

/// Parked cars (mapping arrangement keyed by the town seed, changes keyed by the pass seed)
/// and actors of a pass.
PassContents preparePass(const Town& town, const PassConfig& config);

}  // namespace sim
}  // namespace gmm_localization
