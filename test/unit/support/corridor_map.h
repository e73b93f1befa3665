#pragma once
// Test support: a straight corridor along x (ground everywhere between walls at y = +-3 m), the
// map on which every translation along x scores the same.

#include <cmath>
#include <memory>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace testing {

/// A straight corridor along x: ground everywhere, walls at y = +-3 m.
inline GmmMap corridorMap(const MapGeometry& g) {
  GmmMap map(g);
  for (int32_t ty = -1; ty <= 0; ++ty) {
    for (int32_t tx = -2; tx <= 1; ++tx) {
      auto tile = std::make_shared<GmmTile>(TileId{tx, ty}, g.tile_size_cells);
      const CellIndex o = g.tileOrigin({tx, ty});
      for (int ly = 0; ly < g.tile_size_cells; ++ly) {
        for (int lx = 0; lx < g.tile_size_cells; ++lx) {
          const double y = g.cellCenter({o.x + lx, o.y + ly}).y();
          GaussianMixture1D& cell = tile->at(lx, ly);
          if (std::abs(std::abs(y) - 3.0) < 0.15) {
            cell.add({0.2f, 0.0f, 0.03f});
            cell.add({0.8f, 2.0f, 1.2f});
          } else if (std::abs(y) < 3.0) {
            cell.add({1.0f, 0.0f, 0.03f});
          }
        }
      }
      map.insert(tile);
    }
  }
  return map;
}

/// corridorMap on 128-cell tiles, rasterized with the default options over its chunks.
inline ChunkMap corridorChunks() {
  MapGeometry g;
  g.tile_size_cells = 128;
  const GmmMap map = corridorMap(g);
  const RasterOptions ro;
  ChunkMap chunks(g, ro);
  for (int cy = -2; cy <= 1; ++cy) {
    for (int cx = -3; cx <= 2; ++cx) chunks.insert(rasterizeChunk(map, {cx, cy}, ro).value());
  }
  return chunks;
}

/// A scan of the corridor from its centre: both walls and the floor over x in [-20, 20] m.
inline PointList corridorScan() {
  PointList scan;
  for (double x = -20.0; x <= 20.0; x += 0.1) {
    for (double z = 0.2; z < 4.0; z += 0.2) {
      scan.emplace_back(x, 3.0f, z);
      scan.emplace_back(x, -3.0f, z);
    }
    for (double y = -2.8; y <= 2.8; y += 0.4) scan.emplace_back(x, y, 0.0f);
  }
  return scan;
}

}  // namespace testing
}  // namespace gmm_localization
