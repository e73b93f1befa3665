#pragma once
// Route: a drive through the street grid as a sequence of intersections (nodes), and its lane
// path: the centre of the outer right-hand lane, straight along roads and circular arcs
// through turns (the curvature limit is the turn radius). Like the paper's Downtown drive,
// the planner prefers roads already driven in the other direction, so several roads are
// traversed both ways. The path starts and ends mid-block.

#include <utility>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/town.h"

namespace gmm_localization {
namespace sim {

struct GridNode {
  int i = 0, j = 0;  ///< indices into Town::roadX() / roadY()
  bool operator==(const GridNode& o) const { return i == o.i && j == o.j; }
};

struct RouteConfig {
  uint64_t seed = 7;
  /// Target path length [m]; planning adds blocks until the path is about this long.
  double length_m = 3000.0;
  /// Explicit node sequence (adjacent nodes, no U-turns); overrides planning when not empty.
  std::vector<GridNode> nodes;
  /// Turn radii of the lane path [m] (curvature limits).
  double right_turn_radius_m = 9.0;
  double left_turn_radius_m = 14.0;
  Status validate() const;
};

/// A point of the lane path.
struct PathPoint {
  Eigen::Vector2d position;
  double heading_rad;  ///< direction of travel, counter-clockwise from +x
  double curvature;    ///< [1/m], positive turning left
};

class Route {
 public:
  static Result<Route> plan(const Town& town, const RouteConfig& config);

  const std::vector<GridNode>& nodes() const { return nodes_; }
  double length() const { return length_; }
  /// Lane path at distance s in [0, length()] (clamped).
  PathPoint at(double s) const;
  /// Distances along the path where it passes each intermediate intersection.
  const std::vector<double>& nodeStations() const { return stations_; }
  /// Share of the driven road length whose opposite direction is also driven, in [0, 1].
  double bothDirectionsShare() const { return both_share_; }

 private:
  struct Piece {
    double s0, length;
    Eigen::Vector2d start;
    double heading0, curvature;
  };
  Status buildPath(const Town& town, const RouteConfig& config);
  std::vector<GridNode> nodes_;
  std::vector<Piece> pieces_;
  std::vector<double> stations_;
  double length_ = 0.0;
  double both_share_ = 0.0;
};

}  // namespace sim
}  // namespace gmm_localization
