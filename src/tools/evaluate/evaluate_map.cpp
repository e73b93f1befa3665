#include "evaluate/evaluate_map.h"

#include <chrono>

#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/raster/raster_region.h"
#include "gmm_localization/ros/map_server_load.h"

namespace gmm_localization {
namespace eval {

Result<std::shared_ptr<const ChunkMap>> rasterizeAlongRoute(const std::string& map_directory,
                                                            const RasterOptions& options,
                                                            const Trajectory& route,
                                                            double radius_m, int threads,
                                                            RouteMapStats* stats, MapLayer wanted) {
  using R = Result<std::shared_ptr<const ChunkMap>>;
  const auto t0 = std::chrono::steady_clock::now();
  auto store = MapStore::open(map_directory);
  if (!store) return R::failure(store.error() + node::layerHint(map_directory, wanted));
  const std::string layer = node::layerProblem(*store, wanted);
  if (!layer.empty()) return R::failure(layer);

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
  RegionStats region;
  auto map = rasterizeRegion(*store, options, centres, radius_m, threads, &region);
  if (!map) return R::failure(map.error());
  if (map->size() == 0) {
    return R::failure("map '" + map_directory + "' has no data within " + std::to_string(radius_m) +
                      " m of the route");
  }
  if (stats != nullptr) {
    stats->tiles = region.tiles;
    stats->chunks = region.chunks;
    stats->bytes = region.bytes;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return std::shared_ptr<const ChunkMap>(std::make_shared<ChunkMap>(std::move(*map)));
}

}  // namespace eval
}  // namespace gmm_localization
