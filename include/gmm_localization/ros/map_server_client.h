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
//
// One map server at a time: the publisher (callerid) of the first valid index is adopted, and
// map_version only orders the indices of that publisher. A well-formed index from any other
// publisher is ignored with a reason (ignoredIndices(), lastIgnoredReason()), however new its
// version, as long as the adopted publisher has spoken (a valid index or chunk) within
// publisher_timeout_s of wall time; after that silence (the server is gone) the next valid
// index from another publisher takes over, as a new map. Chunks from a known publisher other
// than the adopted one are rejected (kInvalid). The map server re-sends its latched index
// every index_period_s (map_server.h) so that a live server is never silent that long.
// Publishers are known through the ros::MessageEvent overloads (subscribe with
// `void cb(const ros::MessageEvent<const MapIndex>&)`); the ConstPtr overloads carry no
// publisher: all their messages count as one unnamed publisher (the rules above then reduce to
// the map_version order).

#include <map>
#include <string>
#include <vector>

#include <ros/message_event.h>
#include <ros/time.h>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/RasterChunk.h"
#include "gmm_localization/core/map/georeference.h"
#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {
namespace node {

/// Geometry and raster options described by an index.
MapGeometry geometryOf(const MapIndex& index);
RasterOptions rasterOptionsOf(const MapIndex& index);
/// The inverse, for the publisher of an index: writes geometry and raster into index's fields
/// (geometryOf and rasterOptionsOf read them back unchanged); its other fields are not touched.
void toMsg(const MapGeometry& geometry, const RasterOptions& raster, MapIndex& index);
/// The map's georeference in an index, and back (fields: MapIndex.msg).
void toMsg(const Georeference& georeference, MapIndex& index);
Georeference georeferenceOf(const MapIndex& index);

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
    kInvalid,  ///< fromMsg failed, the chunk disagrees with the index, or it comes from a
               ///< publisher other than the adopted map server: ignored
  };

  /// Wall time the adopted map server must have been silent before another publisher's index
  /// is adopted [s]: several of the server's index_period_s (1 s by default).
  static constexpr double kDefaultPublisherTimeoutS = 5.0;
  /// publisher_timeout_s: see kDefaultPublisherTimeoutS (a value that is not > 0 takes it).
  explicit MapServerClient(double publisher_timeout_s = kDefaultPublisherTimeoutS);

  /// error (optional) receives the reason for kInvalid / kStale.
  ChunkVerdict onChunk(const RasterChunk::ConstPtr& msg, std::string* error = nullptr);
  /// The same, knowing the publisher (getPublisherName) and the wall time of receipt.
  ChunkVerdict onChunk(const ros::MessageEvent<const RasterChunk>& event,
                       std::string* error = nullptr);
  /// `publisher` empty: unknown (always accepted, never refreshes the adopted one's silence).
  ChunkVerdict onChunk(const RasterChunk::ConstPtr& msg, const std::string& publisher,
                       ros::WallTime received, std::string* error = nullptr);

  /// Adopts the index unless it is invalid (validateIndex), from a publisher other than the
  /// adopted one (see the file comment), or older than the adopted one; returns the number of
  /// chunks dropped by it. error (optional) receives the reason when the index is rejected as
  /// invalid or ignored as foreign (for a throttled warning), and is cleared otherwise.
  size_t onIndex(const MapIndex::ConstPtr& index, std::string* error = nullptr);
  /// The same, knowing the publisher (getPublisherName) and the wall time of receipt.
  size_t onIndex(const ros::MessageEvent<const MapIndex>& event, std::string* error = nullptr);
  size_t onIndex(const MapIndex::ConstPtr& index, const std::string& publisher,
                 ros::WallTime received, std::string* error = nullptr);
  /// Indices rejected as invalid so far.
  size_t rejectedIndices() const { return rejected_indices_; }
  /// Well-formed indices ignored so far because another publisher is adopted.
  size_t ignoredIndices() const { return ignored_indices_; }
  /// Why the last one was ignored (empty when none was).
  const std::string& lastIgnoredReason() const { return last_ignored_reason_; }
  /// The adopted map server (callerid; empty before the first index or when unknown).
  const std::string& publisher() const { return publisher_; }
  /// Times another publisher took over after the adopted one fell silent.
  size_t publisherSwitches() const { return publisher_switches_; }

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
    std::string publisher;  ///< empty: unknown
  };
  bool matchesIndex(const RasterChunk& msg, std::string* error) const;
  /// Whether an index from `publisher` may be adopted now; else why not (error).
  bool mayAdopt(const MapIndex& index, const std::string& publisher, ros::WallTime received,
                std::string* error);
  /// Drops the waiting chunks of known publishers other than `publisher`.
  void keepWaitingFrom(const std::string& publisher);
  /// Forgets the adopted server and everything it sent (another one takes over); returns the
  /// number of chunks dropped.
  size_t dropAdopted(const std::string& next_publisher);

  double publisher_timeout_s_;
  MapIndex::ConstPtr index_;
  std::string publisher_;
  ros::WallTime last_heard_;  ///< last valid index or chunk from publisher_
  size_t rejected_indices_ = 0;
  size_t ignored_indices_ = 0;
  size_t publisher_switches_ = 0;
  std::string last_ignored_reason_;
  ChunkMap map_;
  std::map<ChunkId, Held> held_;
  /// Chunks whose version has no index yet: version -> id -> chunk.
  std::map<uint64_t, std::map<ChunkId, Held>> waiting_;
};

}  // namespace node
}  // namespace gmm_localization
