#pragma once
// Test support: a straight corridor along x (ground everywhere between walls at y = +-3 m), the
// map on which every translation along x scores the same.

#include <cmath>
#include <memory>

#include "gmm_localization/core/map/gmm_tile.h"

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

}  // namespace testing
}  // namespace gmm_localization
