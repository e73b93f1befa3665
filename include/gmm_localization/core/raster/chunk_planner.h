#pragma once
// The map server's pure planning logic (no ROS, no threads, no I/O): which raster chunks the
// vehicle needs, in which order, which held chunks and cached tiles may go, and where the
// vehicle is according to the sources the server has.
//
// Frames and units: everything is in the map frame [m]. A chunk (cx, cy) covers global cells
// [cx * C, (cx + 1) * C) per axis, C = 2^chunk_shift (map_chunk.h), i.e. the square
// [origin + cx * C * res, origin + (cx + 1) * C * res) per axis.
//
// A chunk "has data" when any tile of the map overlaps the cells its rasterization reads: its
// own C x C cells plus the +x/+y strip of R = 2^num_layers - 1 cells that its coarse layers'
// blocks reach into (chunkReadTiles, chunk_reach.h). Serving such chunks even when their own cells
// are empty keeps the coarse layers admissible bounds near the map's -x/-y edges: an absent chunk
// reads as the floor everywhere, which would understate a block that reaches into data.

#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/raster/map_chunk.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {

/// A map-frame point [m] around which chunks are served (the vehicle, or a pose hint).
using PlanCentre = Eigen::Vector2d;

class ChunkPlanner {
 public:
  /// tiles_present: the tiles the map holds (MapStore::tileIds()).
  ChunkPlanner(const MapGeometry& geometry, const RasterOptions& raster,
               const std::vector<TileId>& tiles_present);

  const MapGeometry& geometry() const { return geometry_; }
  const RasterOptions& raster() const { return raster_; }
  /// Chunk edge [m].
  double chunkEdgeM() const { return geometry_.resolution_m * raster_.chunkCells(); }

  /// Map-frame lower-left corner of a chunk [m].
  Eigen::Vector2d chunkMin(ChunkId id) const;
  /// Distance from p to the chunk's square [m] (0 inside).
  double distanceToChunk(ChunkId id, const PlanCentre& p) const;
  /// Smallest distanceToChunk over the centres; +infinity when there is none.
  double distanceToChunk(ChunkId id, const std::vector<PlanCentre>& centres) const;
  /// Distance from p to the tile's square [m] (0 inside).
  double distanceToTile(TileId id, const PlanCentre& p) const;
  double distanceToTile(TileId id, const std::vector<PlanCentre>& centres) const;

  /// Tiles of the map that chunk `id` reads (chunkReadTiles() that the map holds), ascending.
  std::vector<TileId> tilesFor(ChunkId id) const;
  bool hasData(ChunkId id) const { return !tilesFor(id).empty(); }

  /// Chunks with data whose square lies within radius_m of any centre, ordered by the distance
  /// from the nearest centre to the chunk's centre (nearest first; ties by id). Non-finite
  /// centres are ignored; radius_m < 0 gives none.
  std::vector<ChunkId> needed(const std::vector<PlanCentre>& centres, double radius_m) const;

  /// The chunks of `held` farther than keep_radius_m from every centre (all of them when there
  /// is no centre: callers only evict once they know where the vehicle is).
  std::vector<ChunkId> toEvict(const std::vector<ChunkId>& held,
                               const std::vector<PlanCentre>& centres, double keep_radius_m) const;

 private:
  MapGeometry geometry_;
  RasterOptions raster_;
  std::unordered_set<TileId, TileIdHash> tiles_;
};

/// What the map server knows about the vehicle's position, each in the map frame [m].
struct PositionSources {
  std::optional<PlanCentre> tf;       ///< map -> base_link now (lookup succeeded this cycle)
  std::optional<PlanCentre> last_tf;  ///< the last successful TF lookup, however old
  double last_tf_age_s = 0.0;         ///< wall time since that lookup [s]
  std::optional<PlanCentre> hint;     ///< the last pose received on pose_hint
  double hint_age_s = 0.0;            ///< wall time since that pose arrived [s]
  std::optional<PlanCentre> initial;  ///< the configured initial position
};

struct CentreSelection {
  std::vector<PlanCentre> centres;
  std::string source;  ///< "tf", "tf+pose_hint", "pose_hint", "last_tf", "initial" or "none"
};

/// Where to serve chunks:
///  - TF answers: its position, plus a pose hint younger than hint_hold_s (a relocalisation:
///    the matcher needs the map there before the EKF moves TF);
///  - else the more recent of the pose hint and the last TF position (a TF dropout keeps the
///    current chunks);
///  - else the configured initial position; else nothing (source "none").
CentreSelection selectCentres(const PositionSources& sources, double hint_hold_s);

}  // namespace gmm_localization
