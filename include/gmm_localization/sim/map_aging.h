#pragma once
// Map aging: what changes in a town between the mapping drive and a localization drive a few
// months later, beyond the parked cars and the snow that a pass models anyway:
//  - construction sites: a fence of 2 m metal panels around two or three consecutive parking
//    slots (and 1 m of the sidewalk behind them), sometimes with a shipping container inside;
//  - shipping containers (20 ft ISO, 6.06 x 2.44 x 2.59 m) standing in parking slots;
//  - grown trees: a share of the street trees has a larger, lower crown;
//  - repaved road stretches: fresh, darker asphalt over the full road width, its lane paint
//    either not yet applied or repainted a few decimetres to one side.
// Objects are placed per km of road centreline, so a route meets about the same number per km
// in any town size. Added objects carry kLabelDynamic; parked cars under them are removed by the
// World. A repaved stretch keeps its geometry (only the surface shading changes, as the snow
// cover does), so its points keep their label. Deterministic for the seed. Applied by
// World::create to localization passes only: the mapping pass is what the town is aged from.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/materials.h"
#include "gmm_localization/sim/mesh.h"
#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

enum class MapAgingMode { kNone, kRealistic };

/// "none" or "realistic"; anything else is a failure naming the value.
Result<MapAgingMode> parseMapAgingMode(const std::string& name);

/// Densities are per km of road centreline (both kerbs together). docs/simulator.md gives the
/// reasoning behind each default (a town a few months after the mapping drive).
struct MapAgingConfig {
  MapAgingMode mode = MapAgingMode::kNone;
  double sites_per_km = 1.0;                ///< construction sites
  double site_container_probability = 0.5;  ///< a site holds a container
  double containers_per_km = 1.5;           ///< containers alone in a parking slot
  double tree_share = 0.25;                 ///< share of street trees with a grown crown
  double tree_growth_min_m = 0.3;           ///< crown growth, outward and downward [m]
  double tree_growth_max_m = 0.6;
  double repaved_per_km = 0.5;  ///< repaved stretches (within one road segment each)
  double repaved_min_m = 30.0;  ///< stretch length range [m] (at most the segment's length)
  double repaved_max_m = 80.0;
  double repaint_probability = 0.5;  ///< stretch repainted (shifted); otherwise no paint yet
  double paint_shift_min_m = 0.3;    ///< lateral shift of repainted lines [m]
  double paint_shift_max_m = 0.6;
  uint64_t seed = 1;
  /// Ranges: densities in [0, 50] per km, probabilities and share in [0, 1], 0 <= min <= max
  /// for growth (<= 3 m), stretch length (>= 1 m) and shift (<= 3 m).
  Status validate() const;
};

/// A rectangle on the ground: centre, heading of its length axis, half extents [m].
struct Footprint {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double yaw_rad = 0.0;
  double half_length_m = 0.0;
  double half_width_m = 0.0;
  bool overlaps(const Footprint& other) const;
};

struct ConstructionSite {
  Footprint fence;  ///< the fenced area (parking lane, 0.3 m of the lane, 1 m sidewalk)
  bool has_container = false;
  Footprint container;  ///< inside the fence, on the road (when has_container)
};

struct GrownTree {
  size_t tree = 0;  ///< index into Town::trees()
  double growth_m = 0.0;
};

struct RepavedStretch {
  Eigen::AlignedBox2d area;    ///< full road width (curb to curb) x the stretch
  Eigen::Vector2d lateral;     ///< unit vector across the road
  bool repainted = false;      ///< false: no paint yet
  double paint_shift_m = 0.0;  ///< repainted lines sit this far along `lateral` (signed)
};

/// The changes of one aged pass.
struct MapAging {
  std::vector<ConstructionSite> sites;
  std::vector<Footprint> containers;  ///< standing alone in parking slots
  std::vector<GrownTree> grown_trees;
  std::vector<RepavedStretch> repaved;
  size_t removed_parked_cars = 0;  ///< filled in by World::create

  bool empty() const {
    return sites.empty() && containers.empty() && grown_trees.empty() && repaved.empty();
  }
  /// True if a site's fence area or a container overlaps `f` (a parked car there goes).
  bool blocks(const Footprint& f) const;
  /// The repaved stretch containing (x, y), or nullptr.
  const RepavedStretch* repavedAt(double x, double y) const;
};

/// Shipping container (20 ft ISO) outer dimensions [m].
constexpr double kContainerLengthM = 6.06;
constexpr double kContainerWidthM = 2.44;
constexpr double kContainerHeightM = 2.59;

/// Plans the changes for `town` (mode none: nothing).
MapAging planMapAging(const Town& town, const MapAgingConfig& config);

/// Appends fences, containers and grown crowns (kLabelDynamic) to `mesh`; objects stand on
/// `surface(x, y)` [m] (the ground including any snow cover).
void addMapAgingMesh(const Town& town, const MapAging& aging,
                     const std::function<double(double, double)>& surface, TriangleMesh* mesh);

/// What a ray that hit the road's asphalt at (x, y) sees: lane paint (the town's, or a repaved
/// stretch's repainted lines), fresh asphalt on a repaved stretch, or the old asphalt.
Material roadSurfaceAt(const Town& town, const MapAging& aging, double x, double y);

}  // namespace sim
}  // namespace gmm_localization
