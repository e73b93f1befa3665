// The read rule of a raster chunk (chunk_reach.h), as a property of the rasterizer on seeded
// random maps, geometries, raster options and chunk ids (negative ones included):
//  - sufficient: a chunk rasterized from only the tiles chunkReadTiles() names, or from those
//    tiles with every cell outside chunkReadCells() cleared, equals bit for bit the chunk
//    rasterized from the whole map (so the rasterizer reads no cell outside the rectangle);
//  - tight: a single mixture at the rectangle's far corner shows in the chunk's coarsest layer,
//    one just outside the rectangle leaves the chunk at the floor everywhere.
#include "gmm_localization/core/raster/chunk_reach.h"

#include <algorithm>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/random_map.h"

namespace gmm_localization {
namespace {

struct Case {
  uint32_t seed = 0;
  MapGeometry geometry;
  RasterOptions options;
  ChunkId id;

  std::string describe() const {
    std::ostringstream s;
    s << "seed " << seed << ": tile " << geometry.tile_size_cells << " cells, chunk_shift "
      << options.chunk_shift << ", num_layers " << options.num_layers << ", z period "
      << options.z_coarsening_period << ", chunk (" << id.x << ", " << id.y << ")";
    return s.str();
  }
};

Case randomCase(uint32_t seed) {
  std::mt19937 rng(seed);
  auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  Case c;
  c.seed = seed;
  c.geometry.resolution_m = 0.2;
  c.geometry.tile_size_cells = uniform(8, 40);  // mostly not aligned with the chunks
  c.geometry.origin_x_m = 0.1 * uniform(-100, 100);
  c.geometry.origin_y_m = 0.1 * uniform(-100, 100);
  c.options.chunk_shift = uniform(4, 5);
  c.options.num_layers = uniform(0, c.options.chunk_shift);
  c.options.z_coarsening_period = uniform(0, 2);
  c.options.z_step_m = 0.1;
  c.id = {uniform(-4, 3), uniform(-4, 3)};
  return c;
}

/// A random map whose tiles cover the chunk's read rectangle with one tile to spare each side.
GmmMap surroundingMap(const Case& c) {
  const CellRect read = chunkReadCells(c.id, c.options);
  const int64_t s = c.geometry.tile_size_cells;
  const TileId lo = c.geometry.tileOf({read.lo.x - s, read.lo.y - s});
  const TileId hi = c.geometry.tileOf({read.hi.x + s, read.hi.y + s});
  return testing::randomMap(c.seed, c.geometry, lo.x, lo.y, hi.x - lo.x + 1, hi.y - lo.y + 1);
}

/// The tiles of `map` that `keep` names; with `clip`, copies whose cells outside it are empty.
GmmMap subMap(const GmmMap& map, const std::vector<TileId>& keep, const CellRect* clip) {
  GmmMap out(map.geometry());
  for (const TileId& t : keep) {
    const GmmTileConstPtr tile = map.tile(t);
    if (!tile) continue;
    if (clip == nullptr) {
      out.insert(tile);
      continue;
    }
    auto copy = std::make_shared<GmmTile>(*tile);
    const CellIndex o = map.geometry().tileOrigin(t);
    for (int32_t ly = 0; ly < copy->sizeCells(); ++ly) {
      for (int32_t lx = 0; lx < copy->sizeCells(); ++lx) {
        if (!clip->contains({o.x + lx, o.y + ly})) copy->at(lx, ly) = GaussianMixture1D();
      }
    }
    out.insert(copy);
  }
  return out;
}

/// A map holding one strong ground mixture (z = 0) at cell c and nothing else.
GmmMap singleCellMap(const MapGeometry& geometry, const CellIndex& c) {
  GmmMap map(geometry);
  const TileId t = geometry.tileOf(c);
  auto tile = std::make_shared<GmmTile>(t, geometry.tile_size_cells);
  const CellIndex o = geometry.tileOrigin(t);
  tile->at(static_cast<int32_t>(c.x - o.x), static_cast<int32_t>(c.y - o.y)).add({1.f, 0.f, 0.05f});
  map.insert(tile);
  return map;
}

MapChunkConstPtr rasterize(const GmmMap& map, const Case& c) {
  auto r = rasterizeChunk(map, c.id, c.options);
  EXPECT_TRUE(r.ok()) << r.error();
  return r.ok() ? r.value() : nullptr;
}

bool allFloor(const MapChunk& chunk) {
  for (int k = 0; k < chunk.numLayers(); ++k) {
    if (chunk.layer(k).value_count != 0) return false;
  }
  for (const GaussianMixture1D& g : chunk.mixtures()) {
    if (!g.empty()) return false;
  }
  return true;
}

TEST(ChunkReach, RectangleIsTheChunkPlusTheReachTowardsPlusXY) {
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 3;
  EXPECT_EQ(chunkReachCells(o), 7);
  const CellRect r = chunkReadCells({-2, 1}, o);
  EXPECT_EQ(r.lo, (CellIndex{-64, 32}));
  EXPECT_EQ(r.hi, (CellIndex{-64 + 32 + 7 - 1, 32 + 32 + 7 - 1}));
  EXPECT_EQ(r.widthCells(), 39);
  EXPECT_EQ(r.heightCells(), 39);
  o.num_layers = 0;
  EXPECT_EQ(chunkReachCells(o), 0);
  EXPECT_EQ(chunkReadCells({-2, 1}, o).hi, (CellIndex{-33, 63}));
}

TEST(ChunkReach, TilesCoveringAreEveryOverlappingTileAscending) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int64_t> cell(-200, 200), size(0, 90);
  for (int trial = 0; trial < 200; ++trial) {
    MapGeometry g;
    g.tile_size_cells = 8 + trial % 33;
    CellRect r;
    r.lo = {cell(rng), cell(rng)};
    r.hi = {r.lo.x + size(rng), r.lo.y + size(rng)};
    const std::vector<TileId> got = tilesCovering(g, r);
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
    std::set<TileId> expected;
    for (int32_t tx = -40; tx <= 40; ++tx) {
      for (int32_t ty = -40; ty <= 40; ++ty) {
        const CellIndex o = g.tileOrigin({tx, ty});
        const int64_t s = g.tile_size_cells;
        if (o.x <= r.hi.x && o.x + s - 1 >= r.lo.x && o.y <= r.hi.y && o.y + s - 1 >= r.lo.y) {
          expected.insert({tx, ty});
        }
      }
    }
    EXPECT_EQ(std::set<TileId>(got.begin(), got.end()), expected) << "trial " << trial;
    EXPECT_EQ(got.size(), expected.size()) << "duplicates, trial " << trial;
  }
}

TEST(ChunkReach, NamedTilesAndCellsSufficeForABitIdenticalChunk) {
  int with_reach_into_other_tiles = 0;
  for (uint32_t seed = 1; seed <= 40; ++seed) {
    const Case c = randomCase(seed);
    SCOPED_TRACE(c.describe());
    const GmmMap full = surroundingMap(c);
    const MapChunkConstPtr want = rasterize(full, c);
    ASSERT_NE(want, nullptr);

    const std::vector<TileId> named = chunkReadTiles(c.geometry, c.id, c.options);
    const MapChunkConstPtr from_tiles = rasterize(subMap(full, named, nullptr), c);
    ASSERT_NE(from_tiles, nullptr);
    EXPECT_TRUE(from_tiles->sameTables(*want));
    EXPECT_EQ(from_tiles->mixtures(), want->mixtures());

    const CellRect read = chunkReadCells(c.id, c.options);
    const MapChunkConstPtr from_cells = rasterize(subMap(full, named, &read), c);
    ASSERT_NE(from_cells, nullptr);
    EXPECT_TRUE(from_cells->sameTables(*want));
    EXPECT_EQ(from_cells->mixtures(), want->mixtures());

    // The planner names the same tiles, restricted to those the map holds.
    std::vector<TileId> present;
    for (const auto& kv : full.tiles()) present.push_back(kv.first);
    EXPECT_EQ(ChunkPlanner(c.geometry, c.options, present).tilesFor(c.id), named);

    // The test means something: the reach often crosses into tiles the chunk's own cells miss.
    CellRect own = read;
    own.hi = {read.lo.x + c.options.chunkCells() - 1, read.lo.y + c.options.chunkCells() - 1};
    if (tilesCovering(c.geometry, own).size() < named.size()) ++with_reach_into_other_tiles;
  }
  EXPECT_GE(with_reach_into_other_tiles, 10);
}

TEST(ChunkReach, RectangleIsTight) {
  for (uint32_t seed = 101; seed <= 140; ++seed) {
    const Case c = randomCase(seed);
    SCOPED_TRACE(c.describe());
    const CellRect read = chunkReadCells(c.id, c.options);
    const int last = c.options.chunkCells() - 1;

    // The far corner is read: it is the last base cell of the top layer's block at the
    // chunk's last cell.
    const MapChunkConstPtr corner = rasterize(singleCellMap(c.geometry, read.hi), c);
    ASSERT_NE(corner, nullptr);
    EXPECT_GT(corner->value(c.options.num_layers, 0, last, last), 0);
    // The near corner is the chunk's own first cell.
    const MapChunkConstPtr first = rasterize(singleCellMap(c.geometry, read.lo), c);
    ASSERT_NE(first, nullptr);
    EXPECT_GT(first->value(0, 0, 0, 0), 0);

    // Cells just outside the rectangle, on each side, are not read.
    for (const CellIndex& outside :
         {CellIndex{read.hi.x + 1, read.hi.y}, CellIndex{read.hi.x, read.hi.y + 1},
          CellIndex{read.lo.x - 1, read.lo.y}, CellIndex{read.lo.x, read.lo.y - 1}}) {
      const MapChunkConstPtr chunk = rasterize(singleCellMap(c.geometry, outside), c);
      ASSERT_NE(chunk, nullptr);
      EXPECT_TRUE(allFloor(*chunk)) << "cell (" << outside.x << ", " << outside.y << ")";
    }
  }
}

}  // namespace
}  // namespace gmm_localization
