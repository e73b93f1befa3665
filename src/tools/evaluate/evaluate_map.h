#pragma once
// The rasterized map `evaluate` searches: the chunks the map server would serve along the
// ground-truth route (core/raster/chunk_planner.h decides which), rasterized up front on worker
// threads by rasterizeRegion (core/raster/raster_region.h) with the same raster options.

#include <memory>
#include <string>
#include <vector>

#include "evaluate/evaluate_metrics.h"
#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/reflectivity_layer.h"
#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/raster_options.h"
#include "gmm_localization/ros/map_server_options.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace eval {

/// The map server's raster keys: node::loadRasterOptions (ros/map_server_options.h).
using node::loadRasterOptions;

struct RouteMapStats {
  size_t tiles = 0;
  size_t chunks = 0;
  size_t bytes = 0;
  double seconds = 0.0;  ///< wall time to load and rasterize
};

/// Rasterizes every chunk with data within radius_m of the route (ground-truth samples at least
/// every spacing_m), on `threads` threads. Fails with the reason (unreadable map, bad tile, not
/// the `wanted` layer: then how to build it).
Result<std::shared_ptr<const ChunkMap>> rasterizeAlongRoute(const std::string& map_directory,
                                                            const RasterOptions& options,
                                                            const Trajectory& route,
                                                            double radius_m, int threads,
                                                            RouteMapStats* stats = nullptr,
                                                            MapLayer wanted = MapLayer::kHeight);

}  // namespace eval
}  // namespace gmm_localization
