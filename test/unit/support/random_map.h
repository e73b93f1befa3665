#pragma once
// Test support: seeded random Gaussian mixture maps and point sets.

#include <random>

#include "gmm_localization/core/map/gmm_tile.h"

namespace gmm_localization {
namespace testing {

/// A map of tiles_x x tiles_y tiles (starting at tile (tx0, ty0)) whose cells hold 0..K random
/// components: a ground-like narrow one and wide "structure" ones. empty_share of cells is empty.
inline GmmMap randomMap(uint32_t seed, const MapGeometry& geometry, int tx0, int ty0, int tiles_x,
                        int tiles_y, double empty_share = 0.3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  GmmMap map(geometry);
  for (int ty = ty0; ty < ty0 + tiles_y; ++ty) {
    for (int tx = tx0; tx < tx0 + tiles_x; ++tx) {
      auto tile = std::make_shared<GmmTile>(TileId{tx, ty}, geometry.tile_size_cells);
      for (auto& cell : tile->cells()) {
        if (u(rng) < empty_share) continue;
        const int k = 1 + static_cast<int>(u(rng) * 2.0);
        double wsum = 0.0;
        double w[3];
        for (int j = 0; j < k; ++j) wsum += (w[j] = 0.2 + u(rng));
        for (int j = 0; j < k; ++j) {
          const bool ground = j == 0;
          const double mean = ground ? 0.3 * (u(rng) - 0.5) : 0.5 + 6.0 * u(rng);
          const double sigma = ground ? 0.03 + 0.05 * u(rng) : 0.1 + 2.0 * u(rng);
          cell.add({static_cast<float>(w[j] / wsum), static_cast<float>(mean),
                    static_cast<float>(sigma)});
        }
      }
      map.insert(tile);
    }
  }
  return map;
}

}  // namespace testing
}  // namespace gmm_localization
