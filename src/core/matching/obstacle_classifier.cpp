#include "gmm_localization/core/matching/obstacle_classifier.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {

namespace {

/// Map-frame |x|, |y| beyond which a pose is not used [m].
constexpr double kMaxPoseOffsetM = 1e7;
/// Pose cell index bound: keeps every cell index of the window far inside int64 and its chunk
/// ids inside int32.
constexpr double kMaxPoseCells = 1e9;
/// Bound on the chunk pointers of the lookup window (8 MB); only a geometry with cells far
/// below the manifest's minimum resolution could reach it.
constexpr int64_t kMaxWindowChunks = int64_t{1} << 20;

double effectiveRange(const ObstacleOptions& options) {
  const double r = options.max_range_m;
  if (!std::isfinite(r)) return kMaxObstacleRangeM;
  return std::min(std::max(r, 1.0), kMaxObstacleRangeM);
}

bool poseUsable(const MapGeometry& g, const Pose6& pose) {
  const double v[] = {pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw};
  for (double x : v) {
    if (!std::isfinite(x)) return false;
  }
  const double cells_x = std::abs(pose.x - g.origin_x_m) / g.resolution_m;
  const double cells_y = std::abs(pose.y - g.origin_y_m) / g.resolution_m;
  return std::abs(pose.x) <= kMaxPoseOffsetM && std::abs(pose.y) <= kMaxPoseOffsetM &&
         cells_x < kMaxPoseCells && cells_y < kMaxPoseCells;
}

}  // namespace

ObstacleLabels classifyObstacles(const ChunkMap& map, const PointList& base_points,
                                 const Pose6& pose, const ObstacleOptions& options,
                                 TaskPool* pool) {
  ObstacleLabels out;
  out.label.assign(base_points.size(), PointClass::kUnknown);
  out.mahalanobis.assign(base_points.size(), std::numeric_limits<float>::infinity());
  if (base_points.empty()) return out;
  const MapGeometry& g = map.geometry();
  if (!g.validate().empty() || !poseUsable(g, pose)) {
    out.unclassified = base_points.size();
    return out;
  }
  const double max_range = effectiveRange(options);
  auto inRange = [&](const Eigen::Vector3f& q) {
    return q.allFinite() && q.cast<double>().norm() <= max_range;
  };
  // Cells under the classified points: a dense chunk grid over their extent (bounded by
  // max_range, so by the sensor, not by the input).
  const Eigen::Isometry3d T = toIsometry(pose);
  double r = 0.0;
  for (const Eigen::Vector3f& p : base_points) {
    if (inRange(p)) r = std::max<double>(r, p.cast<double>().norm());
  }
  const CellIndex lo = g.cellAt(pose.x - r - 1.0, pose.y - r - 1.0);
  const CellIndex hi = g.cellAt(pose.x + r + 1.0, pose.y + r + 1.0);
  const int shift = map.options().chunk_shift;
  if (((hi.x >> shift) - (lo.x >> shift) + 1) * ((hi.y >> shift) - (lo.y >> shift) + 1) >
      kMaxWindowChunks) {
    out.unclassified = base_points.size();
    return out;
  }
  const RasterWindow window(map, lo.x, lo.y, hi.x, hi.y);
  // Blocks of points in parallel, each with its own counters (added after).
  constexpr size_t kBlock = 8192;
  const size_t blocks = (base_points.size() + kBlock - 1) / kBlock;
  struct Counts {
    size_t obstacles = 0, over_empty_cells = 0, unclassified = 0;
  };
  std::vector<Counts> counts(blocks);
  // Each block in batches: first every point's map-frame height and cell mixture, its cache
  // line requested ahead (the cells of consecutive points lie far apart in memory, so each read
  // would otherwise wait for memory in turn), then the distances. The same values as one pass.
  constexpr size_t kBatch = 64;
  parallelFor(blocks > 1 ? pool : nullptr, static_cast<int>(blocks), [&](int b) {
    Counts& n = counts[static_cast<size_t>(b)];
    const size_t end = std::min(base_points.size(), (static_cast<size_t>(b) + 1) * kBlock);
    double z[kBatch];
    bool in_range[kBatch];
    const GaussianMixture1D* cell[kBatch];
    for (size_t first = static_cast<size_t>(b) * kBlock; first < end; first += kBatch) {
      const size_t count = std::min(kBatch, end - first);
      for (size_t k = 0; k < count; ++k) {
        cell[k] = nullptr;
        const Eigen::Vector3f& q = base_points[first + k];
        in_range[k] = inRange(q);
        if (!in_range[k]) continue;
        const Eigen::Vector3d p = T * q.cast<double>();
        z[k] = p.z();
        const CellIndex c = g.cellAt(p.x(), p.y());
        const MapChunk* chunk = window.chunk(c.x, c.y);
        if (chunk != nullptr && chunk->hasMixtures()) {
          const int mask = chunk->cells() - 1;
          cell[k] = &chunk->mixture(static_cast<int>(c.x & mask), static_cast<int>(c.y & mask));
          __builtin_prefetch(cell[k]);  // a mixture may straddle two cache lines
          __builtin_prefetch(reinterpret_cast<const char*>(cell[k] + 1) - 1);
        }
      }
      for (size_t k = 0; k < count; ++k) {
        const size_t i = first + k;
        if (!in_range[k]) {
          ++n.unclassified;
          continue;
        }
        const double d = cell[k] != nullptr ? cell[k]->mahalanobis(z[k])
                                            : std::numeric_limits<double>::infinity();
        out.mahalanobis[i] = static_cast<float>(d);
        if (d <= options.mahalanobis_threshold) {
          out.label[i] = PointClass::kMap;
        } else {
          out.label[i] = PointClass::kObstacle;
          ++n.obstacles;
          if (!std::isfinite(d)) ++n.over_empty_cells;
        }
      }
    }
  });
  for (const Counts& n : counts) {
    out.obstacles += n.obstacles;
    out.over_empty_cells += n.over_empty_cells;
    out.unclassified += n.unclassified;
  }
  return out;
}

}  // namespace gmm_localization
