#pragma once
// The exact log-likelihood of a cloud in the parametric map (Eq. 1), continuous in x and y, for
// the hill-climbing refinement of Algorithm 1.
//
// Per point: the floored log-likelihoods max(ll_floor, log p_c(z)) of the 3 x 3 cells around
// the point, averaged with Gaussian weights of the point's distance to each cell centre (kernel
// sigma about half a cell, like the builder's blur). Empty cells and absent chunks contribute
// the floor. Units: nats.

#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {

/// What ExactScorer::scoreReusing keeps per point of one pose: the 3 x 3 block's first cell,
/// the point's height and the nine floored cell log-likelihoods it read there.
struct CellBlockMemo {
  int64_t cx = 0, cy = 0;
  double z = 0.0;
  double ll[9] = {};
};

class ExactScorer {
 public:
  /// Scores points within radius_m [m] of (center_x, center_y) in the map frame at constant
  /// cost per cell (a dense grid of the chunks there); points beyond it score the floor.
  ExactScorer(const ChunkMap& map, double ll_floor, double center_x_m, double center_y_m,
              double radius_m, double kernel_sigma_m = 0.1);

  /// Interpolated, floored log-likelihood of one map-frame point [nats].
  double pointLogLikelihood(const Eigen::Vector3d& p_map) const;
  /// Sum over `base_points` (base_link frame) placed at `pose` [nats]: partial sums over
  /// blocks of kBlockPoints points (in parallel on `pool` when given), added in block order, so
  /// the sum is the same bit for bit with or without a pool and for any thread count.
  double score(const PointList& base_points, const Pose6& pose, TaskPool* pool = nullptr) const;
  static constexpr size_t kBlockPoints = 128;
  /// score() for the hill climb's neighbouring poses: the points are placed heading last
  /// (yaw about z after pitch and roll, so a step in x, y or heading leaves every height
  /// unchanged, bit for bit), and a point whose block and height equal those in `reuse` (the
  /// same points at the pose the step was taken from; null or empty: none) takes its nine cell
  /// values from there instead of evaluating the mixtures again. `out` receives this pose's
  /// (resized to the points). The value equals score()'s up to the rounding of the placement
  /// (1e-16 relative), and is the same with or without `reuse`, bit for bit. `reuse_also`: a
  /// second memo of the same points to take a point's cells from when `reuse` has not got them
  /// (e.g. the last pose scored one step the same way, whose heights a step in x, y or heading
  /// since has left as they were). Neither may be `out`.
  double scoreReusing(const PointList& base_points, const Pose6& pose,
                      const std::vector<CellBlockMemo>* reuse, std::vector<CellBlockMemo>* out,
                      TaskPool* pool = nullptr,
                      const std::vector<CellBlockMemo>* reuse_also = nullptr) const;
  /// Floored log-likelihood of a point in the single cell containing it (no interpolation).
  double cellLogLikelihood(const Eigen::Vector3d& p_map) const;

 private:
  double floored(const CellIndex& c, double z) const;
  /// The floored log-likelihoods of the 3 x 3 cells around cell (cx, cy) at height z.
  void blockLogLikelihoods(int64_t cx, int64_t cy, double z, double ll[9]) const;
  /// Their Gaussian-weighted mean for a point (fx, fy) cells from the centre cell's centre.
  double weightedMean(double fx, double fy, const double ll[9]) const;
  /// Block sums of per-point values (see score()); block_start(begin, end) runs first in each
  /// block, on the thread that then sums it.
  template <typename PointValue, typename BlockStart>
  double blockSums(size_t points, TaskPool* pool, const PointValue& value,
                   const BlockStart& block_start) const;
  /// The first (lowest x, y) cell of the 3 x 3 block around cell (cx, cy) when the whole block
  /// lies in one loaded chunk (its rows row_cells_ cells apart), else null.
  const MixtureLogTerms* blockFirst(int64_t cx, int64_t cy) const;
  /// blockLogLikelihoods of the block whose blockFirst() is `first`.
  void blockLogLikelihoods(const MixtureLogTerms* first, double z, double ll[9]) const;
  double kernel(double d_cells) const;
  static constexpr int kKernelTableSize = 1538;        // covers [0, 1.5] cells and one guard entry
  static constexpr double kKernelTableScale = 1024.0;  // entries per cell
  const ChunkMap& map_;
  double floor_;
  RasterWindow window_;
  int64_t row_cells_;  ///< cells per chunk row (every chunk of a map has as many)
  std::vector<double> kernel_table_;
};

}  // namespace gmm_localization
