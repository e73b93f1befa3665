#pragma once
// Private to the map builder: pass 2 for one tile. From the tile's merged spill records (its
// columns' z histograms, halo included) to a GmmTile: blur with the neighbouring columns, then
// the weighted EM fit per cell. One instance per worker thread.

#include <memory>
#include <vector>

#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/mapping/em_fitter.h"
#include "gmm_localization/core/mapping/map_builder.h"
#include "map_builder_spill.h"

namespace gmm_localization {
namespace map_builder {

/// The blur kernel's weights for column offsets (dx, dy) in [-r, r]^2, row-major in dy: the
/// Gaussian exp(-d^2 / (2 sigma^2)) of the distance d between the cell centres; sigma = 0 gives
/// weight 1 at the centre and 0 elsewhere.
std::vector<double> blurKernel(double sigma_m, int radius_cells, double resolution_m);

class TileFitter {
 public:
  explicit TileFitter(const MapBuilderOptions& options);

  /// `records` must be sorted and merged (sortAndMerge). Cells whose own column holds fewer
  /// than min_own_points returns stay empty.
  std::shared_ptr<GmmTile> fit(const TileId& id, const std::vector<SpillRecord>& records);
  const EmFitterCounters& emCounters() const { return em_.counters(); }

 private:
  struct Bin {
    int32_t zbin;
    double weight;
    double weight_sq;
  };
  void gatherCell(int ex, int ey, const std::vector<SpillRecord>& records);
  void coarsen();

  int size_;
  int radius_;
  int extent_;  // size_ + 2 radius_
  double z_bin_m_;
  size_t max_samples_;
  uint64_t min_own_points_;
  std::vector<double> kernel_;
  EmFitter em_;
  std::vector<uint32_t> column_begin_;  // extent_^2 + 1 offsets into the records
  std::vector<Bin> bins_;
  std::vector<WeightedSample> samples_;
};

}  // namespace map_builder
}  // namespace gmm_localization
