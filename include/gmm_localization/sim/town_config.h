#pragma once
// TownConfig: the knobs of the procedural downtown (sizes in metres, probabilities in [0, 1]).

#include <cstdint>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace sim {

struct TownConfig {
  uint64_t seed = 1;
  /// Extent of the street grid between the outermost road centrelines (>= 1 km for Downtown).
  double size_x_m = 1200.0;
  double size_y_m = 1200.0;
  /// Road centreline spacing: each gap is drawn in [min, max] and the set rescaled to the size.
  double block_min_m = 90.0;
  double block_max_m = 150.0;
  /// Depth of the ring of blocks outside the outermost roads.
  double outer_margin_m = 50.0;
  /// Cross-section: curb-to-curb road width; per side a parking lane and two traffic lanes.
  double road_width_m = 16.0;
  double parking_lane_m = 2.2;
  double sidewalk_width_m = 4.0;
  double curb_height_m = 0.15;
  /// Height of the road crown at the centreline above the gutter (parabolic profile).
  double crown_height_m = 0.12;
  /// Probability that a parcel holds a building, and the building height range.
  double building_density = 0.85;
  double building_min_height_m = 5.0;
  double building_max_height_m = 35.0;
  /// Street trees along sidewalks: spacing and probability per site (spacing 0 = no trees).
  double tree_spacing_m = 11.0;
  double tree_probability = 0.7;
  /// Street lights along sidewalks (0 = none); signs are placed at intersections.
  double pole_spacing_m = 32.0;
  /// Parking slot length along the kerb.
  double parking_slot_m = 6.5;
  /// Terrain: planar slope (rise per metre) plus one smooth undulation.
  double terrain_slope_x = 0.010;
  double terrain_slope_y = -0.006;
  double terrain_amplitude_m = 1.5;
  double terrain_wavelength_m = 700.0;
  /// Ground mesh vertex spacing along roads and over blocks (across roads: 1 m).
  double ground_mesh_step_m = 2.5;

  /// Checks ranges; the failure names the key, value and allowed range.
  Status validate() const;
};

}  // namespace sim
}  // namespace gmm_localization
