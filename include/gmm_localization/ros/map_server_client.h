#pragma once
// The subscriber's side of the map server's protocol, as a pure class (no master needed): feed
// it every RasterChunk from `map_chunks` and every MapIndex from `map_index`, read the current
// rasterized map from chunks().
//
// Protocol (what map_server guarantees, map_server.h):
//  - map_index (latched) is the authority: the map version, geometry and raster options, and
//    the ids of the chunks the server holds. Each change gets a new index.
//  - header.stamp of chunks and indices comes from one strictly increasing clock, so a chunk
//    published after an index has a later stamp than it, whatever the delivery order across the
//    two topics.
//  - A chunk is kept when its map_version is the index's; a chunk the index does not list is
//    dropped when the index is newer than the chunk (it was evicted), and kept otherwise (the
//    index listing it is on its way). Chunks of a newer version than the index wait for their
//    index; chunks of an older version are ignored.
// Chunks are wrapped with fromMsg (zero copy: they share the message's memory).
// An index is validated before it is adopted (validateIndex): a malformed one (e.g. resolution 0,
// layer counts the raster options reject, extents beyond the map format's physical bounds) is
// rejected with a reason and never replaces the adopted index, whatever its map_version.

#include <map>
#include <string>
#include <vector>

#include <ros/time.h>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/RasterChunk.h"
#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {
namespace node {

/// Geometry and raster options described by an index.
MapGeometry geometryOf(const MapIndex& index);
RasterOptions rasterOptionsOf(const MapIndex& index);

/// Empty when `index` describes a usable map, else which field is wrong and why: the geometry
/// within the map format's physical bounds (checkMapGeometryBounds: resolution in [0.05, 10] m,
/// tile size in [8, 4096], finite bounded origin), valid raster options (RasterOptions::
/// validate: chunk shift, layer counts, z step), as many chunk_x as chunk_y, every listed chunk
/// and the map extent (finite, min <= max) within kMaxMapExtentM (plus one tile or chunk) of
/// the map origin.
std::string validateIndex(const MapIndex& index);

class MapServerClient {
 public:
  enum class ChunkVerdict {
    kAdded,    ///< now in chunks() (or waiting for its index, for a newer version)
    kStale,    ///< older map version, or already evicted by a newer index: ignored
    kInvalid,  ///< fromMsg failed or the chunk disagrees with the index: ignored
  };

  /// error (optional) receives the reason for kInvalid / kStale.
  ChunkVerdict onChunk(const RasterChunk::ConstPtr& msg, std::string* error = nullptr);
  /// Adopts the index unless it is invalid (validateIndex) or older than the adopted one;
  /// returns the number of chunks dropped by it. error (optional) receives the reason when the
  /// index is rejected as invalid (for a throttled warning), and is cleared otherwise.
  size_t onIndex(const MapIndex::ConstPtr& index, std::string* error = nullptr);
  /// Indices rejected as invalid so far.
  size_t rejectedIndices() const { return rejected_indices_; }

  bool hasIndex() const { return index_ != nullptr; }
  const MapIndex::ConstPtr& index() const { return index_; }
  uint64_t mapVersion() const { return index_ ? index_->map_version : 0; }
  /// The rasterized map received so far (empty geometry before the first index).
  const ChunkMap& chunks() const { return map_; }
  /// True when every chunk the index lists has been received.
  bool complete() const;

 private:
  struct Held {
    ros::Time stamp;
    MapChunkConstPtr chunk;
  };
  bool matchesIndex(const RasterChunk& msg, std::string* error) const;

  MapIndex::ConstPtr index_;
  size_t rejected_indices_ = 0;
  ChunkMap map_;
  std::map<ChunkId, Held> held_;
  /// Chunks whose version has no index yet: version -> id -> chunk.
  std::map<uint64_t, std::map<ChunkId, Held>> waiting_;
};

}  // namespace node
}  // namespace gmm_localization
