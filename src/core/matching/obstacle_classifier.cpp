#include "gmm_localization/core/matching/obstacle_classifier.h"

#include <cmath>
#include <limits>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {

ObstacleLabels classifyObstacles(const ChunkMap& map, const PointList& base_points,
                                 const Pose6& pose, const ObstacleOptions& options) {
  ObstacleLabels out;
  out.label.assign(base_points.size(), PointClass::kObstacle);
  out.mahalanobis.assign(base_points.size(), std::numeric_limits<float>::infinity());
  if (base_points.empty()) return out;
  // Cells under the points: a dense chunk grid over the scan's extent.
  const Eigen::Isometry3d T = toIsometry(pose);
  double r = 0.0;
  for (const Eigen::Vector3f& p : base_points) {
    if (p.allFinite()) r = std::max<double>(r, p.head<2>().norm());
  }
  const CellIndex lo = map.geometry().cellAt(pose.x - r - 1.0, pose.y - r - 1.0);
  const CellIndex hi = map.geometry().cellAt(pose.x + r + 1.0, pose.y + r + 1.0);
  const RasterWindow window(map, lo.x, lo.y, hi.x, hi.y);
  for (size_t i = 0; i < base_points.size(); ++i) {
    const Eigen::Vector3f& q = base_points[i];
    if (!q.allFinite()) {
      ++out.obstacles;
      continue;
    }
    const Eigen::Vector3d p = T * q.cast<double>();
    const CellIndex c = map.geometry().cellAt(p.x(), p.y());
    const MapChunk* chunk = window.chunk(c.x, c.y);
    double d = std::numeric_limits<double>::infinity();
    if (chunk != nullptr && chunk->hasMixtures()) {
      const int mask = chunk->cells() - 1;
      d = chunk->mixture(static_cast<int>(c.x & mask), static_cast<int>(c.y & mask))
              .mahalanobis(p.z());
    }
    out.mahalanobis[i] = static_cast<float>(d);
    if (d <= options.mahalanobis_threshold) {
      out.label[i] = PointClass::kMap;
    } else {
      ++out.obstacles;
      if (!std::isfinite(d)) ++out.over_empty_cells;
    }
  }
  return out;
}

}  // namespace gmm_localization
