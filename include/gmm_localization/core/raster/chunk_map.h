#pragma once
// The rasterized map the matcher searches: raster chunks keyed by ChunkId, plus the grid
// geometry and raster options they were built with. Chunks are immutable and shared, so a
// background rasterizer can add chunks while a search holds its own copy of this container.

#include <memory>
#include <unordered_map>

#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/raster/map_chunk.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {

class ChunkMap {
 public:
  ChunkMap() = default;
  ChunkMap(const MapGeometry& geometry, const RasterOptions& options)
      : geometry_(geometry), options_(options) {}

  const MapGeometry& geometry() const { return geometry_; }
  const RasterOptions& options() const { return options_; }

  void insert(MapChunkConstPtr chunk) { chunks_[chunk->id()] = std::move(chunk); }
  void erase(ChunkId id) { chunks_.erase(id); }
  void clear() { chunks_.clear(); }
  MapChunkConstPtr find(ChunkId id) const {
    auto it = chunks_.find(id);
    return it == chunks_.end() ? nullptr : it->second;
  }
  const std::unordered_map<ChunkId, MapChunkConstPtr, ChunkIdHash>& chunks() const {
    return chunks_;
  }
  size_t size() const { return chunks_.size(); }

  ChunkId chunkOf(const CellIndex& c) const {
    return {static_cast<int32_t>(c.x >> options_.chunk_shift),
            static_cast<int32_t>(c.y >> options_.chunk_shift)};
  }
  /// Global z bin of a map-frame height [m].
  int32_t zBin(double z_m) const {
    return static_cast<int32_t>(floorToInt(z_m / options_.z_step_m));
  }

  /// Layer-k value at a global cell and base z bin; 0 (the floor) where no chunk is loaded.
  uint8_t value(int layer, const CellIndex& c, int32_t zb) const {
    const MapChunk* chunk = chunkAt(c);
    if (chunk == nullptr) return 0;
    const int mask = chunk->cells() - 1;
    return chunk->value(layer, zb, static_cast<int>(c.x & mask), static_cast<int>(c.y & mask));
  }
  /// The cell's parametric mixture, or nullptr where no chunk is loaded.
  const GaussianMixture1D* mixture(const CellIndex& c) const {
    const MapChunk* chunk = chunkAt(c);
    if (chunk == nullptr || !chunk->hasMixtures()) return nullptr;
    const int mask = chunk->cells() - 1;
    return &chunk->mixture(static_cast<int>(c.x & mask), static_cast<int>(c.y & mask));
  }

  /// Memory held by all chunks [bytes].
  size_t bytes() const {
    size_t total = 0;
    for (const auto& kv : chunks_) total += kv.second->bytes();
    return total;
  }

 private:
  const MapChunk* chunkAt(const CellIndex& c) const {
    auto it = chunks_.find(chunkOf(c));
    return it == chunks_.end() ? nullptr : it->second.get();
  }

  MapGeometry geometry_;
  RasterOptions options_;
  std::unordered_map<ChunkId, MapChunkConstPtr, ChunkIdHash> chunks_;
};

}  // namespace gmm_localization
