#pragma once
// Obstacle classification (paper V-C): each scan point, placed at the registered pose, is
// labelled map or obstacle by its Mahalanobis distance to its cell's mixture; points over empty
// cells or outside the loaded map cannot be explained by the map and are obstacles.

#include <cstdint>
#include <vector>

#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {

enum class PointClass : uint8_t { kMap = 0, kObstacle = 1 };

struct ObstacleOptions {
  double mahalanobis_threshold = 3.0;  ///< |z - mu| / sigma of the nearest component
};

struct ObstacleLabels {
  std::vector<PointClass> label;   ///< one per input point
  std::vector<float> mahalanobis;  ///< distance per point; +inf over empty or unloaded cells
  size_t obstacles = 0;
  size_t over_empty_cells = 0;  ///< obstacles over empty cells or outside the loaded map
};

/// Labels `base_points` (base_link) at `pose`. Non-finite points are labelled obstacle with
/// distance +inf.
ObstacleLabels classifyObstacles(const ChunkMap& map, const PointList& base_points,
                                 const Pose6& pose, const ObstacleOptions& options);

}  // namespace gmm_localization
