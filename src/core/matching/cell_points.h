#pragma once
// A point set rotated once per heading of a search window and discretised into cells and z
// bins (search_problem.h: "rotate once, then translations are integer cell offsets"), sorted
// for near-sequential table reads and merged where points share a cell and bin. Private to the
// matching stage.

#include <cstdint>
#include <vector>

#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {
namespace search_detail {

struct RotatedPoints {
  std::vector<std::vector<CellPoint>> per_heading;  ///< one list per heading index
  /// Cells the points cover at translation (0, 0) over all headings.
  int64_t gx_min = 0, gy_min = 0, gx_max = 0, gy_max = 0;
};

/// `points` (levelled base frame) at every heading of `window`, their cells relative to
/// translation (0, 0) (cell - half) and their z bins of `map` at height z0_m + z.
RotatedPoints rotatePoints(const ChunkMap& map, const PointList& points, const SearchWindow& window,
                           double z0_m, TaskPool* pool);

}  // namespace search_detail
}  // namespace gmm_localization
