#pragma once
// Test support: the geometry of the seeded random maps of random_map.h that the search and
// certificate tests rasterize, their rasterized chunks, and random scan points.

#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/raster/chunk_map.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/random_map.h"

namespace gmm_localization {
namespace testing {

/// 0.2 m cells in 40-cell (8 m) tiles, the origin off the chunk lattice: windows straddle chunk
/// and tile borders.
inline MapGeometry randomMapGeometry() {
  MapGeometry g;
  g.resolution_m = 0.2;
  g.tile_size_cells = 40;
  g.origin_x_m = -4.1;
  g.origin_y_m = 2.3;
  return g;
}

/// The chunks (cx, cy) with cx and cy in -4..3 of `map`, rasterized with `options` (a chunk
/// that fails to rasterize fails the test).
inline ChunkMap rasterizeRandomMap(const GmmMap& map, const RasterOptions& options) {
  ChunkMap chunks(map.geometry(), options);
  for (int cy = -4; cy <= 3; ++cy) {
    for (int cx = -4; cx <= 3; ++cx) {
      auto r = rasterizeChunk(map, {cx, cy}, options);
      EXPECT_TRUE(r.ok()) << r.error();
      chunks.insert(r.value());
    }
  }
  return chunks;
}

/// The chunks of `full` (cx, cy in -4..3) without a seeded random share of them: a map whose
/// loaded region has holes and edges, where a block may start in a missing chunk and reach
/// into a loaded one.
inline ChunkMap withoutSomeChunks(const ChunkMap& full, uint32_t seed, double drop_share) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ChunkMap out(full.geometry(), full.options());
  for (int cy = -4; cy <= 3; ++cy) {
    for (int cx = -4; cx <= 3; ++cx) {
      MapChunkConstPtr c = full.find({cx, cy});
      if (c != nullptr && u(rng) >= drop_share) out.insert(c);
    }
  }
  return out;
}

/// n points uniform in x, y in [-radius, radius] [m] and z in [-1.8, 4) m.
inline PointList randomPoints(std::mt19937& rng, int n, double radius) {
  std::uniform_real_distribution<double> u(-radius, radius);
  std::uniform_real_distribution<double> z(-1.8, 4.0);
  PointList pts;
  for (int i = 0; i < n; ++i) {
    pts.emplace_back(static_cast<float>(u(rng)), static_cast<float>(u(rng)),
                     static_cast<float>(z(rng)));
  }
  return pts;
}

}  // namespace testing
}  // namespace gmm_localization
