// windowCoverage (core/raster/window_coverage.h) against brute force: on a map of a few chunks
// (an L and an island, the grid's origin off zero), seeded windows whose edges lie on cell
// boundaries, the share of the window's cells whose chunk is loaded, counted cell by cell.

#include "gmm_localization/core/raster/window_coverage.h"

#include <memory>
#include <random>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

ChunkMap lShapedMap() {
  MapGeometry g;
  g.resolution_m = 0.2;
  g.tile_size_cells = 128;
  g.origin_x_m = -3.0;
  g.origin_y_m = 1.0;
  RasterOptions o;
  o.chunk_shift = 5;  // 32 cells, 6.4 m
  ChunkMap map(g, o);
  for (const ChunkId id : {ChunkId{0, 0}, ChunkId{1, 0}, ChunkId{0, 1}, ChunkId{-3, -2}}) {
    map.insert(std::make_shared<const MapChunk>(id, o.chunk_shift));
  }
  return map;
}

TEST(WindowCoverage, EqualsTheShareOfTheWindowsCellsOverLoadedChunks) {
  const ChunkMap map = lShapedMap();
  const MapGeometry& g = map.geometry();
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> centre(-150, 150), half(1, 60);
  // A third of the windows small and over chunks (0, 0) and (1, 0) (cells 0..63 x 0..31).
  std::uniform_int_distribution<int> inside_x(0, 63), inside_y(0, 31), small(1, 12);
  int partial = 0, full = 0, none = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const bool near = trial % 3 == 0;
    const int ci = near ? inside_x(rng) : centre(rng), cj = near ? inside_y(rng) : centre(rng);
    const int hx = near ? small(rng) : half(rng), hy = near ? small(rng) : half(rng);
    // Centre on a cell corner, edges on cell boundaries.
    const double cx = g.origin_x_m + ci * g.resolution_m;
    const double cy = g.origin_y_m + cj * g.resolution_m;
    const WindowCoverage c = windowCoverage(map, cx, cy, hx * g.resolution_m, hy * g.resolution_m);
    int64_t loaded = 0, total = 0;
    for (int64_t i = ci - hx; i < ci + hx; ++i) {
      for (int64_t j = cj - hy; j < cj + hy; ++j) {
        ++total;
        loaded += map.find(map.chunkOf(CellIndex{i, j})) != nullptr ? 1 : 0;
      }
    }
    const double expected = static_cast<double>(loaded) / static_cast<double>(total);
    ASSERT_NEAR(c.loaded_share, expected, 1e-9) << "trial " << trial;
    // The centre's chunk, for a centre inside cell (ci, cj) (a corner may round either way).
    EXPECT_EQ(windowCoverage(map, cx + 0.1, cy + 0.1, 1.0, 1.0).centre_loaded,
              map.find(map.chunkOf(CellIndex{ci, cj})) != nullptr);
    EXPECT_EQ(c.loaded_chunks, 4u);
    partial += expected > 0.0 && expected < 1.0 ? 1 : 0;
    full += expected == 1.0 ? 1 : 0;
    none += expected == 0.0 ? 1 : 0;
  }
  // The seeded windows cover every case.
  EXPECT_GT(partial, 10);
  EXPECT_GT(full, 0);
  EXPECT_GT(none, 10);
}

TEST(WindowCoverage, AnEmptyMapOrAnEmptyWindowCoversNothingAndTheTextSaysHowMuch) {
  const ChunkMap map = lShapedMap();
  EXPECT_DOUBLE_EQ(windowCoverage(map, 0.0, 5.0, 0.0, 10.0).loaded_share, 0.0);
  EXPECT_DOUBLE_EQ(windowCoverage(ChunkMap(), 0.0, 5.0, 10.0, 10.0).loaded_share, 0.0);
  EXPECT_FALSE(windowCoverage(ChunkMap(), 0.0, 5.0, 10.0, 10.0).centre_loaded);
  // The chunk (0, 0) spans x in [-3, 3.4), y in [1, 7.4): a window inside it is all loaded.
  const WindowCoverage inside = windowCoverage(map, 0.0, 4.0, 2.0, 2.0);
  EXPECT_TRUE(inside.centre_loaded);
  EXPECT_DOUBLE_EQ(inside.loaded_share, 1.0);
  const std::string text = describeWindowCoverage(inside, 0.0, 4.0, 2.0);
  EXPECT_NE(text.find("100% of the +-2 m window around (0.0, 4.0)"), std::string::npos) << text;
  EXPECT_NE(text.find("4 chunks"), std::string::npos) << text;
}

}  // namespace
}  // namespace gmm_localization
