#include "map_builder_cells.h"

#include <algorithm>
#include <cmath>

namespace gmm_localization {
namespace map_builder {

std::vector<double> blurKernel(double sigma_m, int radius_cells, double resolution_m) {
  const int width = 2 * radius_cells + 1;
  std::vector<double> k(static_cast<size_t>(width) * width, 0.0);
  for (int dy = -radius_cells; dy <= radius_cells; ++dy) {
    for (int dx = -radius_cells; dx <= radius_cells; ++dx) {
      const double d2 = (dx * dx + dy * dy) * resolution_m * resolution_m;
      double w = (dx == 0 && dy == 0) ? 1.0 : 0.0;
      if (sigma_m > 0.0) w = std::exp(-d2 / (2.0 * sigma_m * sigma_m));
      k[(dy + radius_cells) * width + (dx + radius_cells)] = w;
    }
  }
  return k;
}

TileFitter::TileFitter(const MapBuilderOptions& o)
    : size_(o.geometry.tile_size_cells),
      radius_(o.blur_radius_cells),
      extent_(o.geometry.tile_size_cells + 2 * o.blur_radius_cells),
      z_bin_m_(o.z_bin_m),
      max_samples_(static_cast<size_t>(o.max_samples_per_cell)),
      min_own_points_(static_cast<uint64_t>(std::max(o.min_own_points, 0))),
      kernel_(blurKernel(o.blur_sigma_m, o.blur_radius_cells, o.geometry.resolution_m)),
      em_(o.em) {}

void TileFitter::gatherCell(int ex, int ey, const std::vector<SpillRecord>& records) {
  bins_.clear();
  const int width = 2 * radius_ + 1;
  for (int dy = -radius_; dy <= radius_; ++dy) {
    for (int dx = -radius_; dx <= radius_; ++dx) {
      const double k = kernel_[(dy + radius_) * width + (dx + radius_)];
      if (!(k > 0.0)) continue;
      const size_t col = static_cast<size_t>(ey + dy) * extent_ + (ex + dx);
      for (uint32_t i = column_begin_[col]; i < column_begin_[col + 1]; ++i) {
        const double c = records[i].count;
        bins_.push_back({records[i].zbin, k * c, k * k * c});
      }
    }
  }
  std::sort(bins_.begin(), bins_.end(), [](const Bin& a, const Bin& b) { return a.zbin < b.zbin; });
  size_t out = 0;
  for (size_t i = 0; i < bins_.size(); ++i) {
    if (out > 0 && bins_[out - 1].zbin == bins_[i].zbin) {
      bins_[out - 1].weight += bins_[i].weight;
      bins_[out - 1].weight_sq += bins_[i].weight_sq;
    } else {
      bins_[out++] = bins_[i];
    }
  }
  bins_.resize(out);
  samples_.clear();
  for (const Bin& b : bins_) {
    samples_.push_back({(b.zbin + 0.5) * z_bin_m_, b.weight, b.weight_sq});
  }
  if (samples_.size() > max_samples_) coarsen();
}

void TileFitter::coarsen() {
  // Merge adjacent bins in aligned groups of f = 2, 4, 8 ... bins until the cell has at most
  // max_samples_ samples; a merged sample sits at the weighted centroid of what it merges.
  for (int64_t f = 2; samples_.size() > max_samples_; f *= 2) {
    std::vector<WeightedSample> merged;
    int64_t group = 0;
    double wz = 0.0;
    for (size_t i = 0; i < bins_.size(); ++i) {
      const int64_t g = floorDiv(bins_[i].zbin, f);
      const double z = (bins_[i].zbin + 0.5) * z_bin_m_;
      if (merged.empty() || g != group) {
        if (!merged.empty()) merged.back().z_m = wz / merged.back().weight;
        merged.push_back({0.0, 0.0, 0.0});
        group = g;
        wz = 0.0;
      }
      merged.back().weight += bins_[i].weight;
      merged.back().weight_sq += bins_[i].weight_sq;
      wz += bins_[i].weight * z;
    }
    merged.back().z_m = wz / merged.back().weight;
    samples_.swap(merged);
  }
}

std::shared_ptr<GmmTile> TileFitter::fit(const TileId& id,
                                         const std::vector<SpillRecord>& records) {
  auto tile = std::make_shared<GmmTile>(id, size_);
  // Column index: records are sorted by (ey, ex, zbin), so each column is one run.
  const size_t columns = static_cast<size_t>(extent_) * extent_;
  column_begin_.assign(columns + 1, 0);
  for (const SpillRecord& r : records) {
    if (r.ex < extent_ && r.ey < extent_)
      ++column_begin_[static_cast<size_t>(r.ey) * extent_ + r.ex + 1];
  }
  for (size_t c = 0; c < columns; ++c) column_begin_[c + 1] += column_begin_[c];
  for (int ly = 0; ly < size_; ++ly) {
    for (int lx = 0; lx < size_; ++lx) {
      const int ex = lx + radius_, ey = ly + radius_;
      const size_t own = static_cast<size_t>(ey) * extent_ + ex;
      uint64_t own_points = 0;
      for (uint32_t i = column_begin_[own]; i < column_begin_[own + 1]; ++i)
        own_points += records[i].count;
      if (own_points == 0 || own_points < min_own_points_) continue;
      gatherCell(ex, ey, records);
      tile->at(lx, ly) = em_.fit(samples_).mixture;
    }
  }
  return tile;
}

}  // namespace map_builder
}  // namespace gmm_localization
