#include <algorithm>
#include <climits>
#include <cmath>
#include <vector>

#include "gmm_localization/core/matching/registration.h"

namespace gmm_localization {

double bestHeightOffset(const ChunkMap& map, const PointList& points, const Pose6& prior,
                        double range_m) {
  const double step = map.options().z_step_m;
  const int n = static_cast<int>(std::floor(range_m / step));
  if (n <= 0 || points.empty()) return 0.0;
  const double c = std::cos(prior.yaw), s = std::sin(prior.yaw);
  struct Cell {
    int64_t gx, gy;
    int32_t zb;
  };
  std::vector<Cell> cells(points.size());
  int64_t gx_min = INT64_MAX, gy_min = INT64_MAX, gx_max = INT64_MIN, gy_max = INT64_MIN;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& q = points[i];
    const CellIndex cell =
        map.geometry().cellAt(prior.x + c * q.x() - s * q.y(), prior.y + s * q.x() + c * q.y());
    cells[i] = {cell.x, cell.y, map.zBin(prior.z + q.z())};
    gx_min = std::min(gx_min, cell.x);
    gx_max = std::max(gx_max, cell.x);
    gy_min = std::min(gy_min, cell.y);
    gy_max = std::max(gy_max, cell.y);
  }
  // Direct table reads through a chunk grid (no per-point chunk hash look-up).
  const RasterWindow raster(map, gx_min, gy_min, gx_max, gy_max);
  const int64_t mask = (int64_t{1} << raster.shift()) - 1;
  std::vector<int64_t> score(2 * n + 1, 0);
  for (const Cell& p : cells) {
    const MapChunk* chunk = raster.chunk(p.gx, p.gy);
    if (chunk == nullptr) continue;
    const RasterLayer& L = chunk->layer(0);
    const size_t i =
        (static_cast<size_t>(p.gy & mask) << raster.shift()) + static_cast<size_t>(p.gx & mask);
    for (int k = -n; k <= n; ++k) score[k + n] += MapChunk::spanValue(L, i, p.zb + k);
  }
  // Ties prefer the smallest |offset|.
  int best = n;
  for (int k = 0; k <= 2 * n; ++k) {
    if (score[k] > score[best] ||
        (score[k] == score[best] && std::abs(k - n) < std::abs(best - n))) {
      best = k;
    }
  }
  return score[best] > 0 ? (best - n) * step : 0.0;
}

}  // namespace gmm_localization
