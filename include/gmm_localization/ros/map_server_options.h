#pragma once
// Parameters of the map server (config/map_server.yaml documents each key), loaded once from the
// private node handle and validated; a bad or missing value throws ConfigError naming the key.

#include <optional>
#include <string>

#include <ros/node_handle.h>

#include "gmm_localization/core/map/reflectivity_layer.h"
#include "gmm_localization/core/raster/chunk_engine.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

struct MapServerOptions {
  std::string map_directory;  ///< required: a directory written by build_map
  /// The layer the map must hold (`layer`: height or reflectivity); the server refuses to
  /// start on, or load_map, a map of the other layer.
  MapLayer layer = MapLayer::kHeight;
  std::string map_frame = "map";
  std::string base_frame = "base_link";
  /// Radii, hysteresis, raster options and worker threads (core/raster/chunk_engine.h).
  ChunkEngineOptions engine;
  double update_period_s = 0.5;  ///< vehicle position lookup and index refresh period [s]
  /// The latched index is re-sent, unchanged, at least this often [s]: subscribers tell a live
  /// server from a gone one by it (MapServerClient's publisher timeout, 5 s by default).
  double index_period_s = 1.0;
  /// Served before any TF or pose hint exists (map frame [m]); unset: wait for a position.
  std::optional<PlanCentre> initial_position;
  double pose_hint_hold_s = 10.0;    ///< a pose hint is served beside TF this long [s]
  double map_cloud_radius_m = 60.0;  ///< map_cloud covers cells within this of the vehicle [m]
  double map_cloud_period_s = 2.0;   ///< map_cloud is rebuilt at most this often [s]
};

/// Reads and validates the options (throws ConfigError). The map directory is only required to
/// be non-empty here; the server reports an unreadable map itself.
MapServerOptions loadMapServerOptions(const ParamSource& pnh);

/// The raster keys alone (z_step_m, ll_floor, ll_ceiling, num_layers, z_coarsening_period,
/// chunk_shift), validated: also what `evaluate` reads from config/map_server.yaml.
RasterOptions loadRasterOptions(const ParamSource& pnh);

}  // namespace node
}  // namespace gmm_localization
