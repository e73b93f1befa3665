// What a map index describes (geometry, raster options: geometryOf, rasterOptionsOf, and their
// inverse toMsg for the map server) and whether it is usable (validateIndex), for
// MapServerClient (map_server_client.h).
#include <cmath>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/ros/map_server_client.h"

namespace gmm_localization {
namespace node {

MapGeometry geometryOf(const MapIndex& index) {
  MapGeometry g;
  g.resolution_m = index.resolution_m;
  g.tile_size_cells = index.tile_size_cells;
  g.origin_x_m = index.origin_x_m;
  g.origin_y_m = index.origin_y_m;
  return g;
}

RasterOptions rasterOptionsOf(const MapIndex& index) {
  RasterOptions o;
  o.z_step_m = index.z_step_m;
  o.ll_floor = index.ll_floor;
  o.ll_ceiling = index.ll_ceiling;
  o.num_layers = index.num_layers;
  o.z_coarsening_period = index.z_coarsening_period;
  o.chunk_shift = index.chunk_shift;
  return o;
}

void toMsg(const MapGeometry& geometry, const RasterOptions& raster, MapIndex& index) {
  index.resolution_m = geometry.resolution_m;
  index.tile_size_cells = geometry.tile_size_cells;
  index.origin_x_m = geometry.origin_x_m;
  index.origin_y_m = geometry.origin_y_m;
  index.z_step_m = raster.z_step_m;
  index.ll_floor = raster.ll_floor;
  index.ll_ceiling = raster.ll_ceiling;
  index.num_layers = raster.num_layers;
  index.z_coarsening_period = raster.z_coarsening_period;
  index.chunk_shift = raster.chunk_shift;
}

void toMsg(const Georeference& g, MapIndex& index) {
  index.georeferenced = g.present;
  index.datum = g.datum;
  index.utm_zone = static_cast<uint8_t>(g.hasGrid() ? g.utm_zone : 0);
  index.utm_north = g.utm_north;
  index.epsg = g.hasGrid() ? g.grid().epsg() : 0;
  index.origin_easting_m = g.origin_easting_m;
  index.origin_northing_m = g.origin_northing_m;
  index.origin_up_m = g.origin_up_m;
}

Georeference georeferenceOf(const MapIndex& index) {
  Georeference g;
  g.present = index.georeferenced;
  g.datum = index.datum;
  g.utm_zone = index.utm_zone <= 60 ? index.utm_zone : 0;
  g.utm_north = index.utm_north;
  g.origin_easting_m = index.origin_easting_m;
  g.origin_northing_m = index.origin_northing_m;
  g.origin_up_m = index.origin_up_m;
  return g;
}

std::string validateIndex(const MapIndex& index) {
  const MapGeometry g = geometryOf(index);
  const std::string geometry_error = checkMapGeometryBounds(g);
  if (!geometry_error.empty()) return "invalid geometry: " + geometry_error;
  const std::string raster_error = rasterOptionsOf(index).validate();
  if (!raster_error.empty()) return "invalid raster options: " + raster_error;
  if (index.chunk_x.size() != index.chunk_y.size()) {
    return "chunk_x lists " + std::to_string(index.chunk_x.size()) + " ids, chunk_y " +
           std::to_string(index.chunk_y.size());
  }
  // Every chunk within the map format's extent (one chunk of slack for chunks straddling it).
  const double chunk_m = g.resolution_m * static_cast<double>(1 << index.chunk_shift);
  const double max_chunk = (kMaxMapExtentM + chunk_m) / chunk_m;
  for (size_t i = 0; i < index.chunk_x.size(); ++i) {
    const double far_x =
        std::max(std::abs(double(index.chunk_x[i])), std::abs(double(index.chunk_x[i]) + 1.0));
    const double far_y =
        std::max(std::abs(double(index.chunk_y[i])), std::abs(double(index.chunk_y[i]) + 1.0));
    if (far_x > max_chunk || far_y > max_chunk) {
      return "chunk (" + std::to_string(index.chunk_x[i]) + ", " +
             std::to_string(index.chunk_y[i]) + ") lies beyond " + std::to_string(kMaxMapExtentM) +
             " m of the map origin";
    }
  }
  const double bound = kMaxMapExtentM + g.tileSizeM();
  const double ext[] = {index.min_x_m - g.origin_x_m, index.max_x_m - g.origin_x_m,
                        index.min_y_m - g.origin_y_m, index.max_y_m - g.origin_y_m};
  for (double e : ext) {
    if (!(std::abs(e) <= bound)) {
      std::ostringstream s;
      s << "map extent x [" << index.min_x_m << ", " << index.max_x_m << "], y [" << index.min_y_m
        << ", " << index.max_y_m << "] m is not finite or beyond " << kMaxMapExtentM
        << " m of the origin";
      return s.str();
    }
  }
  if (index.min_x_m > index.max_x_m || index.min_y_m > index.max_y_m) {
    return "map extent has min > max";
  }
  return {};
}

}  // namespace node
}  // namespace gmm_localization
