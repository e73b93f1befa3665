#pragma once
// A raster chunk: a square block of 2^s x 2^s map cells holding, for search, the rasterized
// multiresolution lookup tables of paper IV-B (Fig. 4, 5), and, for refinement and obstacle
// labelling, the parametric Gaussian mixtures of its cells.
//
// Layer k (0 = base) stores one 8-bit quantized log-likelihood per (z bin, cell):
//   base:    L0(zb, c)  = q(max over z in bin zb of log p_c(z)), q = ScoreQuantizer (rounds up)
//   layer k: Lk(zk, c)  = max of L0(zb, c') over c' in the 2^k x 2^k block of cells starting at c
//                         (towards +x and +y) and zb in the group of 2^zShift(k) bins zk.
// Global z bins: bin zb covers z in [zb * z_step, (zb + 1) * z_step) in the map frame. Values
// outside a layer's stored z range, and cells of absent chunks, are 0 (the floor).
// Storage is z-slab-major, [z][y][x] with x fastest, so a row of translations reads contiguously.

#include <cstdint>
#include <memory>
#include <vector>

#include "gmm_localization/core/gaussian_mixture.h"
#include "gmm_localization/core/map_geometry.h"

namespace gmm_localization {

/// Index of a raster chunk: chunk (x, y) holds global cells [x * 2^s, (x + 1) * 2^s) etc.
using ChunkId = TileId;
using ChunkIdHash = TileIdHash;

struct RasterLayer {
  int32_t z_lo = 0;     ///< first stored z bin, in this layer's z units (global bin >> zShift)
  int32_t nz = 0;       ///< number of stored z bins (0: the whole layer is floor)
  int32_t z_shift = 0;  ///< log2 of the base bins grouped per stored bin
  const uint8_t* data = nullptr;  ///< nz * cells * cells values, [z][y][x]
};

class MapChunk {
 public:
  MapChunk(ChunkId id, int shift) : id_(id), shift_(shift) {}

  ChunkId id() const { return id_; }
  int shift() const { return shift_; }
  int cells() const { return 1 << shift_; }
  /// First global cell of this chunk.
  CellIndex origin() const {
    return {static_cast<int64_t>(id_.x) << shift_, static_cast<int64_t>(id_.y) << shift_};
  }

  int numLayers() const { return static_cast<int>(layers_.size()); }
  const RasterLayer& layer(int k) const { return layers_[k]; }

  /// Quantized value of layer k at global z bin zb (base units) and local cell (lx, ly).
  uint8_t value(int k, int32_t zb, int lx, int ly) const {
    const RasterLayer& L = layers_[k];
    const int32_t zi = (zb >> L.z_shift) - L.z_lo;  // arithmetic shift: floor division
    if (zi < 0 || zi >= L.nz) return 0;
    return L.data[(static_cast<size_t>(zi) << (2 * shift_)) + (static_cast<size_t>(ly) << shift_) +
                  static_cast<size_t>(lx)];
  }

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
