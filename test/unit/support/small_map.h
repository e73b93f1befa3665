#pragma once
// Test support: the small in-memory map of the map server's ROS-side gtests (test/ros:
// map_server_client_test, map_server_cloud_test), rasterized in one chunk per tile.

#include <memory>

#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {
namespace testing {

/// 0.2 m cells (the default) in 16-cell tiles, origin (0, 0).
inline MapGeometry smallMapGeometry() {
  MapGeometry g;
  g.tile_size_cells = 16;
  return g;
}

/// 16-cell chunks (one per tile) of 2 layers, the other options at their defaults.
inline RasterOptions smallMapRasterOptions() {
  RasterOptions o;
  o.chunk_shift = 4;
  o.num_layers = 2;
  return o;
}

/// Tiles (0, 0) and (1, 0); every cell holds one component (sigma 0.05 m) at 0.1 x m, x the
/// cell's column in its tile.
inline GmmMap smallMap() {
  GmmMap map(smallMapGeometry());
  for (int tx = 0; tx < 2; ++tx) {
    auto tile = std::make_shared<GmmTile>(TileId{tx, 0}, 16);
    for (int y = 0; y < 16; ++y) {
      for (int x = 0; x < 16; ++x) {
        GaussianMixture1D m;
        m.add({1.f, 0.1f * x, 0.05f});
        tile->at(x, y) = m;
      }
    }
    map.insert(tile);
  }
  return map;
}

}  // namespace testing
}  // namespace gmm_localization
