#pragma once
// Rasterizes a region of a map on disk up front: the chunks the map server would serve around
// some centres, for the offline tools (evaluate, bench_registration, kitti_check). The map
// server itself rasterizes incrementally on its own threads (chunk_engine.h) with the same
// chunk selection (ChunkPlanner::needed) and the same tile rule (chunk_reach.h).
//
// Frames and units: centres are map-frame points [m], radius_m [m].

#include <cstddef>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {

struct RegionStats {
  size_t tiles = 0;             ///< tiles loaded
  size_t chunks = 0;            ///< chunks rasterized
  size_t bytes = 0;             ///< MapChunk::bytes() over those chunks
  double load_seconds = 0.0;    ///< wall time loading the tiles [s]
  double raster_seconds = 0.0;  ///< wall time rasterizing, after the tiles are loaded [s]
};

/// The chunks ChunkPlanner::needed(centres, radius_m) names (chunks with data whose square lies
/// within radius_m of a centre), each rasterized by rasterizeChunk on `threads` threads (values
/// below 1 count as 1; the calling thread is one of them). Loads each tile that
/// ChunkPlanner::tilesFor names for these chunks once, and no other tile, so every chunk equals
/// the chunk rasterized from the whole map. An empty ChunkMap when no chunk with data is within
/// radius_m. Fails with the reason on invalid raster options ("raster options: ...") and on a
/// tile that cannot be loaded. stats, when given, is filled on success.
Result<ChunkMap> rasterizeRegion(const MapStore& store, const RasterOptions& options,
                                 const std::vector<PlanCentre>& centres, double radius_m,
                                 int threads = 1, RegionStats* stats = nullptr);

}  // namespace gmm_localization
