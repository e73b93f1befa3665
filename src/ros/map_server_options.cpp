#include "gmm_localization/ros/map_server_options.h"

#include <cmath>
#include <vector>

#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

RasterOptions loadRasterOptions(const ParamSource& pnh) {
  RasterOptions r;
  r.z_step_m = param(pnh, "z_step_m", r.z_step_m, 0.01, 2.0);
  r.ll_floor = param(pnh, "ll_floor", r.ll_floor, -100.0, 10.0);
  r.ll_ceiling = param(pnh, "ll_ceiling", r.ll_ceiling, -100.0, 20.0);
  r.num_layers = param(pnh, "num_layers", r.num_layers, 0, 10);
  r.z_coarsening_period = param(pnh, "z_coarsening_period", r.z_coarsening_period, 0, 10);
  r.chunk_shift = param(pnh, "chunk_shift", r.chunk_shift, 4, 10);
  requireValid("raster options", r.validate());
  return r;
}

MapServerOptions loadMapServerOptions(const ParamSource& pnh) {
  MapServerOptions o;
  o.map_directory = param<std::string>(pnh, "map_directory", "");
  if (o.map_directory.empty()) {
    throw ConfigError("parameter " + pnh.resolveName("map_directory") +
                      " is required: the directory of a map written by build_map");
  }
  const std::string layer = param<std::string>(pnh, "layer", mapLayerName(o.layer));
  if (layer == "reflectivity") {
    o.layer = MapLayer::kReflectivity;
  } else if (layer != "height") {
    throw ConfigError("parameter " + pnh.resolveName("layer") + " = '" + layer +
                      "' must be height or reflectivity");
  }
  o.map_frame = param<std::string>(pnh, "map_frame", o.map_frame);
  o.base_frame = param<std::string>(pnh, "base_frame", o.base_frame);
  if (o.map_frame.empty() || o.base_frame.empty()) {
    throw ConfigError("parameters map_frame and base_frame must not be empty");
  }

  ChunkEngineOptions& e = o.engine;
  e.raster_radius_m = param(pnh, "raster_radius_m", e.raster_radius_m, 1.0, 2000.0);
  e.tile_cache_radius_m = param(pnh, "tile_cache_radius_m", e.tile_cache_radius_m, 0.0, 2000.0);
  e.hysteresis_m = param(pnh, "hysteresis_m", e.hysteresis_m, 0.0, 1000.0);
  e.worker_threads = param(pnh, "worker_threads", e.worker_threads, 1, 16);
  e.tile_retry_period_s = param(pnh, "tile_retry_period_s", e.tile_retry_period_s, 0.01, 86400.0);
  e.raster = loadRasterOptions(pnh);
  requireValid("map server options", e.validate());

  o.update_period_s = param(pnh, "update_period_s", o.update_period_s, 0.02, 10.0);
  o.index_period_s = param(pnh, "index_period_s", o.index_period_s, 0.05, 60.0);
  o.pose_hint_hold_s = param(pnh, "pose_hint_hold_s", o.pose_hint_hold_s, 0.0, 3600.0);
  o.map_cloud_radius_m = param(pnh, "map_cloud_radius_m", o.map_cloud_radius_m, 0.0, 2000.0);
  o.map_cloud_period_s = param(pnh, "map_cloud_period_s", o.map_cloud_period_s, 0.05, 600.0);

  const auto initial = param<std::vector<double>>(pnh, "initial_position", {});
  if (!initial.empty()) {
    if (initial.size() != 2 || !std::isfinite(initial[0]) || !std::isfinite(initial[1])) {
      throw ConfigError("parameter " + pnh.resolveName("initial_position") +
                        " must be empty or [x, y] in the map frame [m]");
    }
    o.initial_position = PlanCentre(initial[0], initial[1]);
  }
  return o;
}

}  // namespace node
}  // namespace gmm_localization
