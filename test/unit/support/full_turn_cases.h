#pragma once
// Test support for the global (heading-interval) search and its certificate: small rasterized
// random maps and random full-turn windows over them.

#include <cstdint>
#include <limits>
#include <random>

#include "gmm_localization/core/matching/global_search.h"
#include "gmm_localization/core/matching/grid_search.h"
#include "support/random_chunk_map.h"
#include "support/random_map.h"

namespace gmm_localization {
namespace testing {

/// Chunks of 32 x 32 cells with 4 coarse layers, rasterized from a random map whose cells are
/// empty with probability `empty_share`.
inline ChunkMap smallRandomChunks(uint32_t seed, double empty_share,
                                  int z_coarsening_period = RasterOptions().z_coarsening_period) {
  const GmmMap map = randomMap(seed, randomMapGeometry(), -2, -2, 4, 4, empty_share);
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 4;
  o.z_coarsening_period = z_coarsening_period;
  return rasterizeRandomMap(map, o);
}

/// A full-turn window (heading step 0.1 rad: 63 headings) of half extent 0.6-2.2 m around a
/// random prior in [-xy, xy]^2.
inline SearchWindow fullTurnWindow(std::mt19937& rng, double xy) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Pose6 prior;
  prior.x = -xy + 2.0 * xy * u(rng);
  prior.y = -xy + 2.0 * xy * u(rng);
  prior.z = u(rng);
  prior.yaw = 6.28 * u(rng);
  return SearchWindow::fromExtent(prior, 0.6 + 1.6 * u(rng), 0.6 + 1.6 * u(rng), 3.1416, 0.1, 0.2);
}

/// Global search options without a score floor: random points on these maps score far below
/// the optimum of a real scan in its map, which the default floor is set for.
inline GlobalSearchOptions withoutScoreFloor(GlobalSearchOptions o = GlobalSearchOptions()) {
  o.min_score_per_point = -std::numeric_limits<double>::infinity();
  return o;
}

}  // namespace testing
}  // namespace gmm_localization
