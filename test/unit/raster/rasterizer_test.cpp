// Bound admissibility (DESIGN.md 4.7): every multiresolution layer value is >= the exact max of
// the base values it bounds, brute-forced on random maps, including chunk and tile borders.

#include "gmm_localization/core/raster/rasterizer.h"

#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/raster/chunk_map.h"
#include "support/random_map.h"

namespace gmm_localization {
namespace {

RasterOptions smallOptions(int z_coarsening_period) {
  RasterOptions o;
  o.chunk_shift = 4;  // 16-cell chunks: many chunk borders in a small map
  o.num_layers = 3;
  o.z_step_m = 0.1;
  o.z_coarsening_period = z_coarsening_period;
  return o;
}

MapGeometry smallGeometry() {
  MapGeometry g;
  g.resolution_m = 0.2;
  g.tile_size_cells = 24;  // not a multiple of the chunk size: tile and chunk borders differ
  g.origin_x_m = -3.0;
  g.origin_y_m = 1.0;
  return g;
}

ChunkMap rasterizeAll(const GmmMap& map, const RasterOptions& o, int c0, int c1) {
  ChunkMap chunks(map.geometry(), o);
  for (int cy = c0; cy <= c1; ++cy) {
    for (int cx = c0; cx <= c1; ++cx) {
      auto r = rasterizeChunk(map, {cx, cy}, o);
      EXPECT_TRUE(r.ok()) << r.error();
      chunks.insert(r.value());
    }
  }
  return chunks;
}

TEST(Rasterizer, BaseLayerIsQuantizedMaxOverBin) {
  const GmmMap map = testing::randomMap(11, smallGeometry(), -1, -1, 2, 2);
  const RasterOptions o = smallOptions(1);
  const ChunkMap chunks = rasterizeAll(map, o, -2, 1);
  const ScoreQuantizer q(o);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> cell(-30, 30);
  std::uniform_int_distribution<int> bin(-20, 100);
  for (int i = 0; i < 3000; ++i) {
    const CellIndex c{cell(rng), cell(rng)};
    const int zb = bin(rng);
    const GaussianMixture1D* g = map.cell(c);
    const uint8_t expected =
        (g == nullptr || g->empty())
            ? 0
            : q.quantize(g->maxLogLikelihood(zb * o.z_step_m, (zb + 1) * o.z_step_m));
    ASSERT_EQ(chunks.value(0, c, zb), expected) << "cell " << c.x << "," << c.y << " bin " << zb;
  }
}

void checkAdmissible(int period, uint32_t seed) {
  const GmmMap map = testing::randomMap(seed, smallGeometry(), -1, -1, 2, 2, 0.4);
  const RasterOptions o = smallOptions(period);
  // Chunks -3..1 cover every cell of the map (tiles -1..0 span cells -24..23) and beyond.
  const ChunkMap chunks = rasterizeAll(map, o, -3, 1);
  std::mt19937 rng(seed + 1);
  std::uniform_int_distribution<int> cell(-40, 30);
  std::uniform_int_distribution<int> bin(-10, 90);
  int64_t nonzero = 0;
  for (int i = 0; i < 4000; ++i) {
    const CellIndex c{cell(rng), cell(rng)};
    const int zb = bin(rng);
    for (int k = 1; k <= o.num_layers; ++k) {
      const int span = 1 << k;
      const int zgroup = 1 << o.zShift(k);
      const int z0 = (zb >> o.zShift(k)) * (1 << o.zShift(k));  // no left shift of zb < 0
      uint8_t exact = 0;
      for (int dy = 0; dy < span; ++dy) {
        for (int dx = 0; dx < span; ++dx) {
          for (int dz = 0; dz < zgroup; ++dz) {
            exact = std::max(exact, chunks.value(0, {c.x + dx, c.y + dy}, z0 + dz));
          }
        }
      }
      const uint8_t bound = chunks.value(k, c, zb);
      ASSERT_GE(bound, exact) << "layer " << k << " cell " << c.x << "," << c.y << " bin " << zb;
      // Built from exact maxima, the bound is also tight.
      ASSERT_EQ(bound, exact) << "layer " << k << " cell " << c.x << "," << c.y;
      nonzero += exact > 0;
    }
  }
  EXPECT_GT(nonzero, 1000);  // the check exercised real values, not only the floor
}

TEST(Rasterizer, LayersAreAdmissibleAndTight) { checkAdmissible(0, 21); }
TEST(Rasterizer, LayersWithCoarsenedZAreAdmissibleAndTight) {
  checkAdmissible(1, 22);
  checkAdmissible(2, 23);
}

TEST(Rasterizer, AboveFloorRangeContainsEveryValueAboveFloor) {
  GaussianMixture1D g;
  g.add({0.8f, 0.0f, 0.03f});
  g.add({0.2f, 4.0f, 1.5f});
  const double floor = -6.0;
  const auto range = aboveFloorRange(g, floor);
  for (double z = -20.0; z <= 30.0; z += 0.001) {
    if (z < range.first || z > range.second) {
      ASSERT_LT(g.logLikelihood(z), floor) << z;
    }
  }
}

TEST(Rasterizer, RejectsInvalidOptions) {
  RasterOptions o;
  o.z_step_m = 0.0;
  GmmMap map(smallGeometry());
  auto r = rasterizeChunk(map, {0, 0}, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("z_step_m"), std::string::npos);
}

TEST(Rasterizer, EmptyMapGivesFloorEverywhere) {
  GmmMap map(smallGeometry());
  auto r = rasterizeChunk(map, {0, 0}, smallOptions(1));
  ASSERT_TRUE(r.ok());
  for (int k = 0; k <= 3; ++k) EXPECT_EQ(r.value()->value(k, 5, 3, 3), 0);
}

}  // namespace
}  // namespace gmm_localization
