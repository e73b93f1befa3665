#pragma once
// A square tile of Gaussian mixture cells, and the in-memory Gaussian mixture map G: the unit
// the builder writes, the store loads and the rasterizer consumes.

#include <map>
#include <memory>
#include <vector>

#include "gmm_localization/core/map/gaussian_mixture.h"
#include "gmm_localization/core/map/map_geometry.h"

namespace gmm_localization {

class GmmTile {
 public:
  GmmTile(TileId id, int32_t size_cells)
      : id_(id), size_(size_cells), cells_(static_cast<size_t>(size_cells) * size_cells) {}

  TileId id() const { return id_; }
  int32_t sizeCells() const { return size_; }

  /// Cell at local index (lx, ly), 0 <= lx, ly < sizeCells(); storage is row-major in y.
  GaussianMixture1D& at(int32_t lx, int32_t ly) {
    return cells_[static_cast<size_t>(ly) * size_ + lx];
  }
  const GaussianMixture1D& at(int32_t lx, int32_t ly) const {
    return cells_[static_cast<size_t>(ly) * size_ + lx];
  }
  const std::vector<GaussianMixture1D>& cells() const { return cells_; }
  std::vector<GaussianMixture1D>& cells() { return cells_; }

  /// Number of cells holding exactly k components, k = 0..kMaxMixtureComponents.
  std::vector<size_t> componentHistogram() const {
    std::vector<size_t> h(kMaxMixtureComponents + 1, 0);
    for (const auto& c : cells_) ++h[c.size()];
    return h;
  }

 private:
  TileId id_;
  int32_t size_;
  std::vector<GaussianMixture1D> cells_;
};

using GmmTileConstPtr = std::shared_ptr<const GmmTile>;

/// The Gaussian mixture map G held in memory: geometry plus the tiles present. Missing tiles
/// and empty cells both mean "no map data".
class GmmMap {
 public:
  GmmMap() = default;
  explicit GmmMap(const MapGeometry& geometry) : geometry_(geometry) {}

  const MapGeometry& geometry() const { return geometry_; }
  void setGeometry(const MapGeometry& g) { geometry_ = g; }

  /// Adds or replaces a tile. Its size must equal geometry().tile_size_cells.
  void insert(GmmTileConstPtr tile) { tiles_[tile->id()] = std::move(tile); }
  void erase(TileId id) { tiles_.erase(id); }
  GmmTileConstPtr tile(TileId id) const {
    auto it = tiles_.find(id);
    return it == tiles_.end() ? nullptr : it->second;
  }
  const std::map<TileId, GmmTileConstPtr>& tiles() const { return tiles_; }

  /// The cell's mixture, or nullptr when its tile is not present.
  const GaussianMixture1D* cell(const CellIndex& c) const {
    const TileId t = geometry_.tileOf(c);
    auto it = tiles_.find(t);
    if (it == tiles_.end()) return nullptr;
    const CellIndex o = geometry_.tileOrigin(t);
    return &it->second->at(static_cast<int32_t>(c.x - o.x), static_cast<int32_t>(c.y - o.y));
  }

 private:
  MapGeometry geometry_;
  std::map<TileId, GmmTileConstPtr> tiles_;
};

}  // namespace gmm_localization
