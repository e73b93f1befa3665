#pragma once
// The map server's background engine (no ROS): keeps the parametric tiles near the vehicle,
// rasterizes the raster chunks it needs on worker threads, nearest first, and evicts what it has
// left behind. The ROS layer (map_server.h) feeds it the vehicle's position and publishes what it
// produces through the callbacks.
//
// Work cycle of each worker thread (paper IV-B: "rasterized multiresolution maps computed online
// from the parametrized map as a background job"):
//  1. plan (under the state lock): evict held chunks farther than raster_radius + hysteresis
//     from every centre and cached tiles farther than tile_cache_radius + hysteresis; pick the
//     nearest needed chunk that is neither held nor being rasterized (ChunkPlanner);
//  2. load the tiles it reads (ChunkPlanner::tilesFor: the rule of chunk_reach.h) that are not
//     cached (MapStore::loadTile, outside the lock). A tile that fails (CRC, truncated, ...) is
//     remembered as bad, reported once through on_tile_error, and treated as empty: the chunk
//     is still served (degraded). A bad tile is tried again every tile_retry_period_s (the
//     directory may be restored meanwhile): when no needed chunk is pending, a degraded held
//     chunk whose missing tile is due is planned again; if the tile now loads it is reported
//     through on_tile_recovered and the chunk is rasterized again and replaces the held one
//     (same map version); if not, nothing is republished;
//  3. rasterizeChunk (outside the lock), then hand the chunk to on_chunk, which publishes it and
//     returns the chunk to hold (e.g. one sharing the published message's memory), unless the
//     map changed or the chunk left the keep radius meanwhile.
// on_chunk and on_held_changed are called from worker threads (or from switchMap's caller), one
// at a time and in the order of the changes they report (a publication lock serialises them),
// never under the state lock: they may call held(), stats() and mapVersion(), but not
// switchMap() or the destructor.
//
// Failure: create() and switchMap() fail with the reason (unreadable manifest, invalid options,
// a map without tiles) and then change nothing. Nothing else fails: tile errors are reported.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/core/raster/map_chunk.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {

struct ChunkEngineOptions {
  double raster_radius_m = 120.0;      ///< chunks within this of a centre are rasterized [m]
  double tile_cache_radius_m = 130.0;  ///< parametric tiles within this are kept [m]
  double hysteresis_m = 20.0;          ///< extra distance before anything is evicted [m]
  RasterOptions raster;
  int worker_threads = 1;  ///< background rasterization threads, in [1, 16]
  /// A tile that failed to load is tried again after this [s], in [0.01, 86400].
  double tile_retry_period_s = 10.0;

  /// Empty when valid, else the offending field, its value and the allowed range.
  std::string validate() const;
};

/// A snapshot of the engine's state for diagnostics and the map index.
struct ChunkEngineStats {
  uint64_t map_version = 0;
  std::string map_directory;
  size_t tiles_in_map = 0;
  size_t tiles_cached = 0;
  size_t chunks_held = 0;
  size_t chunks_pending = 0;       ///< needed, not held (including those in progress)
  size_t chunks_in_progress = 0;   ///< being rasterized now
  size_t raster_bytes = 0;         ///< MapChunk::bytes() over the held chunks
  uint64_t chunks_rasterized = 0;  ///< since this map was loaded
  double last_raster_ms = 0.0;     ///< rasterizeChunk time of the last chunk [ms]
  double mean_raster_ms = 0.0;
  double max_raster_ms = 0.0;
  double last_tile_load_ms = 0.0;             ///< loadTile time of the last tile loaded [ms]
  std::map<TileId, std::string> tile_errors;  ///< bad tiles of this map and why
  size_t chunks_degraded = 0;  ///< held chunks rasterized without some bad tile they read
  bool has_centres = false;
};

class ChunkEngine {
 public:
  struct Callbacks {
    /// Publishes a new chunk; returns the chunk to hold (the argument itself, or an equivalent
    /// one). Required.
    std::function<MapChunkConstPtr(const MapChunkConstPtr& chunk, uint64_t map_version)> on_chunk;
    /// The held set changed (a chunk added or evicted, or the map switched). Optional.
    std::function<void()> on_held_changed;
    /// A tile could not be loaded; reported once per tile until it loads again. Optional.
    std::function<void(const TileId& tile, const std::string& reason)> on_tile_error;
    /// A tile that had failed loads again (its chunks are being rasterized again). Optional.
    std::function<void(const TileId& tile)> on_tile_recovered;
  };

  /// Opens the map and starts the workers (idle until setCentres()). map_version is the version
  /// of this first map; switchMap() increments it.
  static Result<std::unique_ptr<ChunkEngine>> create(const std::string& map_directory,
                                                     const ChunkEngineOptions& options,
                                                     Callbacks callbacks, uint64_t map_version);
  /// Stops and joins the workers (a chunk being rasterized is finished and dropped).
  ~ChunkEngine();
  ChunkEngine(const ChunkEngine&) = delete;
  ChunkEngine& operator=(const ChunkEngine&) = delete;

  /// Serves chunks around these map-frame points [m] from now on (empty: keep what is held).
  void setCentres(const std::vector<PlanCentre>& centres);

  /// Switches to another map: opens and checks it first (manifest readable, geometry valid, at
  /// least one tile); on success increments the map version, drops every held chunk and cached
  /// tile, reports on_held_changed and starts over around the current centres. On failure the
  /// current map stays served and the reason is returned.
  Status switchMap(const std::string& map_directory);

  /// Held chunks, ordered by id.
  std::vector<MapChunkConstPtr> held() const;
  uint64_t mapVersion() const;
  /// The store of the current map (shared; stays valid after a switch).
  std::shared_ptr<const MapStore> store() const;
  /// Summary of the current map (computed once per map).
  MapSummary mapSummary() const;
  ChunkEngineStats stats() const;

  /// Waits until every needed chunk is held and nothing is in progress, up to timeout_s of
  /// wall time. Returns false on timeout. For tests and tools.
  bool waitIdle(double timeout_s) const;

 private:
  struct Job;
  using Clock = std::chrono::steady_clock;
  struct BadTile {
    std::string reason;
    Clock::time_point retry_at;
  };
  ChunkEngine(const ChunkEngineOptions& options, Callbacks callbacks);
  void installMap(std::shared_ptr<const MapStore> store, uint64_t version);
  void workerLoop();
  /// Plans under the lock; returns false when there is nothing to do.
  bool plan(Job& job, std::vector<ChunkId>& evicted);
  /// A degraded held chunk with a bad tile due for a retry (under the lock), or nullptr.
  const ChunkId* dueRefreshLocked(Clock::time_point now) const;
  /// Fills the job's tiles: cached ones, and those to load (bad ones only when due).
  void collectTilesLocked(Job& job, Clock::time_point now);
  /// Earliest retry of a tile a degraded held chunk lacks (under the lock); max() when none.
  Clock::time_point nextRetryLocked() const;
  void runJob(Job& job);
  bool idleLocked() const;

  const ChunkEngineOptions options_;
  const Callbacks callbacks_;

  std::mutex publish_mutex_;  // serialises callbacks and the state changes they report
  mutable std::mutex mutex_;  // guards everything below
  mutable std::condition_variable wake_;
  mutable std::condition_variable idle_;
  bool stop_ = false;
  bool dirty_ = false;  // centres or map changed, or a job finished: plan again
  uint64_t version_ = 0;
  std::shared_ptr<const MapStore> store_;
  std::unique_ptr<ChunkPlanner> planner_;
  MapSummary summary_;
  std::vector<PlanCentre> centres_;
  std::map<ChunkId, MapChunkConstPtr> held_;
  std::set<ChunkId> in_progress_;
  std::map<TileId, GmmTileConstPtr> tiles_;
  std::map<TileId, BadTile> bad_tiles_;
  std::map<ChunkId, std::set<TileId>> degraded_;  // held chunks -> the bad tiles they lack
  size_t pending_ = 0;                            // needed, not held, at the last plan
  uint64_t rasterized_ = 0;
  double last_raster_ms_ = 0.0, sum_raster_ms_ = 0.0, max_raster_ms_ = 0.0;
  double last_tile_load_ms_ = 0.0;
  std::vector<std::thread> workers_;
};

}  // namespace gmm_localization
