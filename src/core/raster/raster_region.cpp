#include "gmm_localization/core/raster/raster_region.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

Result<ChunkMap> rasterizeRegion(const MapStore& store, const RasterOptions& options,
                                 const std::vector<PlanCentre>& centres, double radius_m,
                                 int threads, RegionStats* stats) {
  using R = Result<ChunkMap>;
  const std::string bad = options.validate();
  if (!bad.empty()) return R::failure("raster options: " + bad);
  const ChunkPlanner planner(store.geometry(), options, store.tileIds());
  const std::vector<ChunkId> chunks = planner.needed(centres, radius_m);

  const auto load_start = Clock::now();
  std::set<TileId> tile_ids;
  for (const ChunkId& c : chunks) {
    for (const TileId& t : planner.tilesFor(c)) tile_ids.insert(t);
  }
  GmmMap gmm(store.geometry());
  for (const TileId& t : tile_ids) {
    auto tile = store.loadTile(t);
    if (!tile) return R::failure(tile.error());
    gmm.insert(tile.value());
  }
  const double load_seconds = secondsSince(load_start);

  const auto raster_start = Clock::now();
  ChunkMap map(store.geometry(), options);
  std::mutex mutex;  // guards map and error
  std::string error;
  std::atomic<size_t> next{0};
  auto work = [&]() {
    for (size_t i = next++; i < chunks.size(); i = next++) {
      auto chunk = rasterizeChunk(gmm, chunks[i], options);
      std::lock_guard<std::mutex> lock(mutex);
      if (!chunk) {
        if (error.empty()) error = chunk.error();
      } else {
        map.insert(chunk.value());
      }
    }
  };
  const size_t wanted = threads > 1 ? static_cast<size_t>(threads) : 1;
  const size_t workers = std::min(wanted, std::max<size_t>(1, chunks.size()));
  std::vector<std::thread> pool;
  for (size_t i = 1; i < workers; ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (!error.empty()) return R::failure("rasterization: " + error);

  if (stats != nullptr) {
    stats->tiles = tile_ids.size();
    stats->chunks = map.size();
    stats->bytes = map.bytes();
    stats->load_seconds = load_seconds;
    stats->raster_seconds = secondsSince(raster_start);
  }
  return map;
}

}  // namespace gmm_localization
