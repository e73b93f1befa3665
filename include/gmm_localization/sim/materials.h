#pragma once
// Surface materials of the simulated town and their LIDAR response at 905 nm.

#include <cstdint>

namespace gmm_localization {
namespace sim {

enum class Material : uint8_t {
  kAsphalt = 0,  ///< road surface; lane markings are painted procedurally (Town::markingAt)
  kConcrete,     ///< sidewalks, curbs
  kGrass,        ///< open lots
  kWall,         ///< building facades (reflectivity varies per building, see kWallBright)
  kWallBright,   ///< light facades
  kGlass,        ///< windows and shop fronts: dark, frequent dropouts
  kRoofing,      ///< overhang slabs, roofs
  kFabric,       ///< awnings
  kBark,         ///< tree trunks
  kFoliage,      ///< tree canopies: porous (rays pass through with some probability)
  kMetal,        ///< poles
  kSign,         ///< retroreflective sign plates
  kCarPaint,     ///< vehicles
  kCarGlass,     ///< vehicle windows
  kTire,         ///< wheels
  kPerson,       ///< pedestrians
  kSnow,         ///< snow cover and snowbanks
  kLaneMarking,  ///< paint (only as a shading result, never on a triangle)
  kAsphaltNew,   ///< fresh asphalt of a repaved stretch (map aging; only as a shading result)
  kCount
};

struct MaterialResponse {
  float reflectivity;   ///< diffuse reflectivity in [0, 1] (maps to intensity ~255 * rho)
  float pass_through;   ///< probability that a ray continues through the surface
  float extra_dropout;  ///< probability of no return on top of the range/power model
};

/// Response table indexed by Material.
const MaterialResponse& materialResponse(Material m);

/// Ground-truth labels carried by every simulated point (PointCloud2 field `label`).
enum PointLabel : uint8_t {
  kLabelStatic = 0,   ///< structure present in the mapping pass (incl. thin snow cover on ground)
  kLabelDynamic = 1,  ///< moving actors, changed parked cars, map-aging objects (map_aging.h)
  kLabelSnow = 2,     ///< falling snow and snowbanks
};

}  // namespace sim
}  // namespace gmm_localization
