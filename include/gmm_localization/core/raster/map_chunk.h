#pragma once
// A raster chunk: a square block of 2^s x 2^s map cells holding, for search, the rasterized
// multiresolution lookup tables of paper IV-B (Fig. 4, 5), and, for refinement and obstacle
// labelling, the parametric Gaussian mixtures of its cells.
//
// Layer k (0 = base) stores one 8-bit quantized log-likelihood per (z bin, cell):
//   base:    L0(zb, c)  = q(max over z in bin zb of log p_c(z)), q = ScoreQuantizer (rounds up)
//   layer k: Lk(zk, c)  = max of L0(zb, c') over c' in the 2^k x 2^k block of cells starting at c
//                         (towards +x and +y) and zb in the group of 2^zShift(k) bins zk.
// Global z bins: bin zb covers z in [zb * z_step, (zb + 1) * z_step) in the map frame.
//
// Storage is sparse in z: per cell, only the span of z bins from its lowest to its highest
// non-zero value is stored (a base cell of ground holds a handful of bins, a wall a few dozen);
// everything outside the span, and every cell of an absent chunk, is 0 (the floor). On the
// simulated Downtown this keeps 3-6% of a dense [z][y][x] table at the base layer.

#include <cstdint>
#include <memory>
#include <vector>

#include "gmm_localization/core/map/gaussian_mixture.h"
#include "gmm_localization/core/map/map_geometry.h"

namespace gmm_localization {

/// Index of a raster chunk: chunk (x, y) holds global cells [x * 2^s, (x + 1) * 2^s) etc.
using ChunkId = TileId;
using ChunkIdHash = TileIdHash;

/// One layer of a chunk. Cell i = ly * cells + lx stores values[spans[2i] .. spans[2i + 2]) for
/// the z bins (in this layer's units) starting at int32(spans[2i + 1]); spans has
/// 2 * cells^2 + 2 entries (a final offset closes the last cell).
struct RasterLayer {
  int32_t z_shift = 0;  ///< log2 of the base z bins grouped per stored bin
  const uint32_t* spans = nullptr;
  const uint8_t* values = nullptr;
  uint32_t value_count = 0;  ///< total stored values
};

class MapChunk {
 public:
  MapChunk(ChunkId id, int shift) : id_(id), shift_(shift) {}

  ChunkId id() const { return id_; }
  int shift() const { return shift_; }
  int cells() const { return 1 << shift_; }
  /// First global cell of this chunk: id * 2^shift, exact for every int32 id (a multiplication:
  /// left-shifting a negative id would be undefined behaviour).
  CellIndex origin() const {
    const int64_t cells_per_chunk = int64_t{1} << shift_;
    return {static_cast<int64_t>(id_.x) * cells_per_chunk,
            static_cast<int64_t>(id_.y) * cells_per_chunk};
  }

  int numLayers() const { return static_cast<int>(layers_.size()); }
  const RasterLayer& layer(int k) const { return layers_[k]; }

  /// Quantized value of layer k at global z bin zb (base units) and local cell (lx, ly).
  uint8_t value(int k, int32_t zb, int lx, int ly) const {
    return spanValue(layers_[k], (static_cast<size_t>(ly) << shift_) + static_cast<size_t>(lx), zb);
  }
  /// The same for cell index i = ly * cells() + lx of layer L.
  static uint8_t spanValue(const RasterLayer& L, size_t i, int32_t zb) {
    const uint32_t begin = L.spans[2 * i];
    const uint32_t n = L.spans[2 * i + 2] - begin;
    // Arithmetic shift: floor division; unsigned compare folds z < 0 into z >= n.
    const uint32_t z =
        static_cast<uint32_t>((zb >> L.z_shift) - static_cast<int32_t>(L.spans[2 * i + 1]));
    return z < n ? L.values[begin + z] : 0;
  }
  /// True when both chunks hold identical tables (ids, layers, spans and values).
  bool sameTables(const MapChunk& other) const;

  /// Parametric mixture of local cell (lx, ly); empty when the map has no data there.
  const GaussianMixture1D& mixture(int lx, int ly) const {
    return mixtures_[(static_cast<size_t>(ly) << shift_) + static_cast<size_t>(lx)];
  }
  bool hasMixtures() const { return !mixtures_.empty(); }
  /// The same mixture prepared for fast evaluation.
  const MixtureLogTerms& logTerms(int lx, int ly) const {
    return terms_[(static_cast<size_t>(ly) << shift_) + static_cast<size_t>(lx)];
  }

  /// Bytes held by the lookup tables and the mixtures.
  size_t bytes() const;

  // --- construction (rasterizer, message conversion) ---
  /// Takes ownership of (or shares) the memory behind the layers; `owner` keeps it alive.
  void setLayers(std::vector<RasterLayer> layers, std::shared_ptr<const void> owner) {
    layers_ = std::move(layers);
    owner_ = std::move(owner);
  }
  /// Sets the cells' mixtures (cells() x cells(), row-major in y) and derives their log terms.
  void setMixtures(std::vector<GaussianMixture1D> m) {
    mixtures_ = std::move(m);
    terms_.clear();
    terms_.reserve(mixtures_.size());
    for (const GaussianMixture1D& g : mixtures_) terms_.emplace_back(g);
  }
  const std::vector<GaussianMixture1D>& mixtures() const { return mixtures_; }

 private:
  ChunkId id_;
  int shift_;
  std::vector<RasterLayer> layers_;
  std::shared_ptr<const void> owner_;
  std::vector<GaussianMixture1D> mixtures_;
  std::vector<MixtureLogTerms> terms_;
};

using MapChunkConstPtr = std::shared_ptr<const MapChunk>;

}  // namespace gmm_localization
