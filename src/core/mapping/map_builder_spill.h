#pragma once
// Private to the map builder: pass 1's per-tile spill files of (cell, z bin, count) records.
// The files are temporary, written and read by the same process, so records go to disk as
// raw structs (the portable byte-by-byte encoding is for the map files only).

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_geometry.h"

namespace gmm_localization {
namespace map_builder {

/// One z-histogram entry of one column, in the tile's extended (halo) coordinates: column
/// (ex, ey) is global cell (tile_origin.x + ex - r, tile_origin.y + ey - r), r = blur radius.
struct SpillRecord {
  uint16_t ex = 0;
  uint16_t ey = 0;
  int32_t zbin = 0;  ///< floor(z / z_bin_m)
  uint32_t count = 0;
};
static_assert(sizeof(SpillRecord) == 12, "SpillRecord must stay packed");

/// Sorts by (ey, ex, zbin) and merges equal keys, summing counts (saturating at 2^32 - 1).
void sortAndMerge(std::vector<SpillRecord>& records);

class SpillStore {
 public:
  /// `directory` must exist; buffer_bytes bounds the records held in memory.
  SpillStore(std::string directory, size_t buffer_bytes);

  /// Buffer for a tile (created on first use); the reference stays valid for the store's life.
  std::vector<SpillRecord>& buffer(const TileId& tile);
  /// Call after appending to a buffer: flushes it, or everything, when over budget.
  Status afterAppend(const TileId& tile, std::vector<SpillRecord>& buffer, size_t appended);
  Status flushAll();

  /// Tiles with a spill file (after flushAll()).
  std::vector<TileId> tiles() const;
  uint64_t fileBytes(const TileId& tile) const;
  uint64_t bytesWritten() const { return bytes_written_; }

  /// All records of a tile, merged and sorted. Thread-safe after flushAll().
  Result<std::vector<SpillRecord>> read(const TileId& tile) const;
  /// Deletes a tile's spill file. Thread-safe after flushAll().
  void remove(const TileId& tile) const;
  std::string path(const TileId& tile) const;

 private:
  Status flush(const TileId& tile, std::vector<SpillRecord>& records);
  Status append(const TileId& tile, const std::vector<SpillRecord>& records, bool truncate);

  std::string dir_;
  size_t max_buffered_records_;
  size_t per_tile_records_;
  size_t buffered_ = 0;
  uint64_t bytes_written_ = 0;
  std::unordered_map<TileId, std::vector<SpillRecord>, TileIdHash> buffers_;
  std::unordered_map<TileId, uint64_t, TileIdHash> file_bytes_;
  std::unordered_map<TileId, uint64_t, TileIdHash> compacted_bytes_;
};

}  // namespace map_builder
}  // namespace gmm_localization
