#pragma once
// Obstacle classification (paper V-C): each scan point, placed at the registered pose, is
// labelled map or obstacle by its Mahalanobis distance to its cell's mixture; points over empty
// cells or outside the loaded map cannot be explained by the map and are obstacles.
//
// Work per scan is bounded by the sensor's physical range: only finite points within
// ObstacleOptions::max_range_m (3D distance from base_link) are classified; the cells looked up
// then span at most 2 * (max_range_m + 1) m around the pose whatever the input holds. Points
// beyond the range, non-finite points, and all points of a non-finite or off-grid pose are
// labelled kUnknown (not classified) and counted in `unclassified`.

#include <cstdint>
#include <vector>

#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {

/// kUnknown: not classified (beyond max_range_m, non-finite, or the pose is unusable).
enum class PointClass : uint8_t { kMap = 0, kObstacle = 1, kUnknown = 2 };

struct ObstacleOptions {
  double mahalanobis_threshold = 3.0;  ///< |z - mu| / sigma of the nearest component
  /// Points farther than this from base_link (3D) are not classified [m]. Clamped to
  /// [1, kMaxObstacleRangeM]; non-finite means kMaxObstacleRangeM. The default is far beyond
  /// the scan filter's default max_range_m (80 m) and any automotive LIDAR's reach.
  double max_range_m = 300.0;
};

/// Upper bound on ObstacleOptions::max_range_m [m].
constexpr double kMaxObstacleRangeM = 1000.0;

struct ObstacleLabels {
  std::vector<PointClass> label;   ///< one per input point
  std::vector<float> mahalanobis;  ///< distance per point; +inf over empty or unloaded cells
                                   ///< and for unclassified points
  size_t obstacles = 0;
  size_t over_empty_cells = 0;  ///< obstacles over empty cells or outside the loaded map
  size_t unclassified = 0;      ///< points labelled kUnknown
};

/// Labels `base_points` (base_link) at `pose`. Non-finite points, points beyond
/// options.max_range_m and every point of a pose that is not finite (or whose x, y lie beyond
/// 1e7 m of the map origin, where cell indices lose meaning) are labelled kUnknown with
/// distance +inf.
/// `pool`: blocks of points in parallel (the same labels and counts).
ObstacleLabels classifyObstacles(const ChunkMap& map, const PointList& base_points,
                                 const Pose6& pose, const ObstacleOptions& options,
                                 TaskPool* pool = nullptr);

}  // namespace gmm_localization
