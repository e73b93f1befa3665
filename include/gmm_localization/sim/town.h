#pragma once
// Town: the layout of a procedural downtown (street grid, terrain, buildings, trees, poles,
// signs, parking slots, sidewalks) and analytic queries on its ground surface. The static
// objects come as one TriangleMesh (label 0); the ground surface is meshed separately by
// buildGroundMesh() (town_mesh.h) so a pass can cover it with snow.
//
// Frame: the map frame (x east, y north, z up, metres). Road centrelines run north-south at
// x = roadX()[i] and east-west at y = roadY()[j]; node (i, j) is their intersection. The grid
// spans [0, size_x] x [0, size_y]; blocks extend outer_margin_m beyond it.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/mesh.h"
#include "gmm_localization/sim/town_config.h"

namespace gmm_localization {
namespace sim {

/// A parking place along a kerb: centre (on the ground), heading along the road [rad].
struct ParkingSlot {
  Eigen::Vector2d center;
  double yaw_rad;
};

/// A straight walkable line (sidewalk centre) from a to b.
struct Walkway {
  Eigen::Vector2d a, b;
};

/// A street tree's canopy: the ellipsoid its foliage blobs are clustered in (blob centres lie
/// within +-rh/2 horizontally and +-0.4 rv vertically of `center`).
struct TreeCrown {
  Eigen::Vector3d center;  ///< map frame [m]
  double radius_h_m;       ///< horizontal semi-axis rh
  double radius_v_m;       ///< vertical semi-axis rv
};

/// Lateral offsets of lane centres from the road centreline [m] (positive = right of travel).
struct LaneOffsets {
  double inner_m;    ///< inner traffic lane (used by moving traffic)
  double outer_m;    ///< outer traffic lane (the ego vehicle's lane)
  double parking_m;  ///< parking lane
};

class Town {
 public:
  static Result<Town> generate(const TownConfig& config);

  const TownConfig& config() const { return config_; }
  const std::vector<double>& roadX() const { return road_x_; }
  const std::vector<double>& roadY() const { return road_y_; }
  int nodesX() const { return static_cast<int>(road_x_.size()); }
  int nodesY() const { return static_cast<int>(road_y_.size()); }
  Eigen::Vector2d nodePosition(int i, int j) const { return {road_x_[i], road_y_[j]}; }
  LaneOffsets laneOffsets() const;
  /// Whole modelled area including the outer blocks.
  Eigen::AlignedBox2d bounds() const;

  /// Smooth terrain height [m]: the level of the gutter (road edge).
  double terrainHeight(double x, double y) const;
  /// Bare ground surface [m]: crowned road, or sidewalk/lot level (terrain + curb height).
  double groundHeight(double x, double y) const;
  /// True if (x, y) lies on a road (between curbs, intersections included).
  bool onRoad(double x, double y) const;
  /// True if (x, y) is on painted road marking (centre line, lane lines, stop lines, crosswalks).
  bool markingAt(double x, double y) const;

  /// Buildings, overhangs, awnings, trees, poles and signs (all label kLabelStatic).
  const TriangleMesh& objects() const { return objects_; }
  const std::vector<ParkingSlot>& parkingSlots() const { return parking_; }
  const std::vector<Walkway>& walkways() const { return walkways_; }
  /// The street trees' canopies, in the order they were built (meshes are in objects()).
  const std::vector<TreeCrown>& trees() const { return trees_; }

  /// Index of the road centreline nearest to v in `lines` (ascending).
  static int nearestLine(const std::vector<double>& lines, double v);

 private:
  friend class TownBuilder;
  TownConfig config_;
  std::vector<double> road_x_, road_y_;
  double phase_x_ = 0.0, phase_y_ = 0.0;
  TriangleMesh objects_;
  std::vector<ParkingSlot> parking_;
  std::vector<Walkway> walkways_;
  std::vector<TreeCrown> trees_;
};

}  // namespace sim
}  // namespace gmm_localization
