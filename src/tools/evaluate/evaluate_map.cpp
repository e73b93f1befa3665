#include "evaluate/evaluate_map.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <set>
#include <thread>

#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace eval {

Result<std::shared_ptr<const ChunkMap>> rasterizeAlongRoute(const std::string& map_directory,
                                                            const RasterOptions& options,
                                                            const Trajectory& route,
                                                            double radius_m, int threads,
                                                            RouteMapStats* stats) {
  using R = Result<std::shared_ptr<const ChunkMap>>;
  const auto t0 = std::chrono::steady_clock::now();
  auto store = MapStore::open(map_directory);
  if (!store) return R::failure(store.error());
  const std::string bad = options.validate();
  if (!bad.empty()) return R::failure("raster options: " + bad);
  const ChunkPlanner planner(store->geometry(), options, store->tileIds());

  // Route points every few metres (the planner measures distances to chunk squares).
  const double spacing_m = 5.0;
  std::vector<PlanCentre> centres;
  for (const PoseStamped2& p : route.samples()) {
    if (centres.empty() || (centres.back() - PlanCentre(p.x, p.y)).norm() >= spacing_m) {
      centres.emplace_back(p.x, p.y);
    }
  }
  if (!route.empty()) {
    centres.emplace_back(route.samples().back().x, route.samples().back().y);
  }
  const std::vector<ChunkId> chunks = planner.needed(centres, radius_m);
  if (chunks.empty()) {
    return R::failure("map '" + map_directory + "' has no data within " + std::to_string(radius_m) +
                      " m of the route");
  }
  std::set<TileId> tile_ids;
  for (const ChunkId& c : chunks) {
    for (const TileId& t : planner.tilesFor(c)) tile_ids.insert(t);
  }
  GmmMap gmm(store->geometry());
  for (const TileId& t : tile_ids) {
    auto tile = store->loadTile(t);
    if (!tile) return R::failure(tile.error());
    gmm.insert(tile.value());
  }

  auto map = std::make_shared<ChunkMap>(store->geometry(), options);
  std::mutex mutex;
  std::atomic<size_t> next{0};
  std::string error;
  auto work = [&]() {
    for (size_t i = next++; i < chunks.size(); i = next++) {
      auto chunk = rasterizeChunk(gmm, chunks[i], options);
      std::lock_guard<std::mutex> lock(mutex);
      if (!chunk) {
        if (error.empty()) error = chunk.error();
      } else {
        map->insert(chunk.value());
      }
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < std::max(1, threads); ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (!error.empty()) return R::failure("rasterization: " + error);
  if (stats != nullptr) {
    stats->tiles = tile_ids.size();
    stats->chunks = map->size();
    stats->bytes = map->bytes();
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return std::shared_ptr<const ChunkMap>(std::move(map));
}

}  // namespace eval
}  // namespace gmm_localization
