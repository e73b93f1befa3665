// The map server's planning logic: which chunks a position needs, in which order, what is
// evicted (with hysteresis), which tiles a chunk reads, and where the vehicle is.
#include "gmm_localization/core/raster/chunk_planner.h"

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

MapGeometry geometry() {
  MapGeometry g;
  g.resolution_m = 0.2;
  g.tile_size_cells = 100;  // 20 m tiles, not aligned with the 25.6 m chunks
  g.origin_x_m = -13.0;
  g.origin_y_m = 7.0;
  return g;
}

RasterOptions raster() {
  RasterOptions r;
  r.chunk_shift = 7;  // 128 cells = 25.6 m
  r.num_layers = 6;   // reach 63 cells = 12.6 m
  return r;
}

std::vector<TileId> tileBlock(int x0, int x1, int y0, int y1) {
  std::vector<TileId> t;
  for (int x = x0; x <= x1; ++x) {
    for (int y = y0; y <= y1; ++y) t.push_back({x, y});
  }
  return t;
}

TEST(ChunkPlanner, NeededMatchesBruteForceAndIsNearestFirst) {
  const ChunkPlanner p(geometry(), raster(), tileBlock(-10, 10, -10, 10));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-150.0, 150.0);
  for (int trial = 0; trial < 20; ++trial) {
    const PlanCentre c(pos(rng), pos(rng));
    const double radius = 30.0 + trial * 3.0;
    const std::vector<ChunkId> needed = p.needed({c}, radius);
    // Brute force over a generous box of chunk ids.
    std::set<ChunkId> expected;
    for (int x = -30; x <= 30; ++x) {
      for (int y = -30; y <= 30; ++y) {
        if (p.distanceToChunk({x, y}, c) <= radius && p.hasData({x, y})) expected.insert({x, y});
      }
    }
    EXPECT_EQ(std::set<ChunkId>(needed.begin(), needed.end()), expected);
    EXPECT_EQ(needed.size(), expected.size()) << "duplicates";
    double last = 0.0;
    const double half = p.chunkEdgeM() / 2;
    for (const ChunkId& id : needed) {
      const double d = (p.chunkMin(id) + Eigen::Vector2d(half, half) - c).norm();
      EXPECT_GE(d, last - 1e-9);
      last = d;
    }
  }
}

TEST(ChunkPlanner, ChunkSquareGeometry) {
  const ChunkPlanner p(geometry(), raster(), tileBlock(0, 0, 0, 0));
  EXPECT_DOUBLE_EQ(p.chunkEdgeM(), 25.6);
  EXPECT_NEAR(p.chunkMin({2, -1}).x(), -13.0 + 51.2, 1e-9);
  EXPECT_NEAR(p.chunkMin({2, -1}).y(), 7.0 - 25.6, 1e-9);
  EXPECT_DOUBLE_EQ(p.distanceToChunk({0, 0}, PlanCentre(-1.0, 10.0)), 0.0);
  EXPECT_NEAR(p.distanceToChunk({0, 0}, PlanCentre(-16.0, 3.0)), 5.0, 1e-9);  // 3-4-5
}

TEST(ChunkPlanner, ChunkReachingIntoDataIsNeeded) {
  // Only tile (0, 0) holds data: cells [0, 100)^2. Chunk (-1, -1) covers cells [-128, 0) but its
  // coarse layers read up to cell 62: it must be served, or the bounds there would read floor.
  const ChunkPlanner p(geometry(), raster(), {{0, 0}});
  EXPECT_TRUE(p.hasData({-1, -1}));
  EXPECT_TRUE(p.hasData({0, 0}));
  EXPECT_FALSE(p.hasData({1, 0}));   // cells [128, 256): beyond the tile
  EXPECT_FALSE(p.hasData({-2, 0}));  // cells [-256, -128) + 63: short of cell 0
  EXPECT_EQ(p.tilesFor({-1, -1}), std::vector<TileId>({{0, 0}}));
}

TEST(ChunkPlanner, TilesForSpansTileBorders) {
  const ChunkPlanner p(geometry(), raster(), tileBlock(-5, 5, -5, 5));
  // Chunk (0, 0): cells [0, 128 + 63) -> tiles 0 and 1 per axis.
  EXPECT_EQ(p.tilesFor({0, 0}), std::vector<TileId>({{0, 0}, {0, 1}, {1, 0}, {1, 1}}));
  // Chunk (1, 0): cells [128, 319) -> tiles 1..3 in x.
  const auto t = p.tilesFor({1, 0});
  EXPECT_EQ(t.size(), 6u);
  EXPECT_EQ(t.front(), (TileId{1, 0}));
  EXPECT_EQ(t.back(), (TileId{3, 1}));
}

TEST(ChunkPlanner, EvictionHasHysteresis) {
  const ChunkPlanner p(geometry(), raster(), tileBlock(-10, 10, -10, 10));
  const PlanCentre start(0.0, 20.0);
  const double radius = 60.0, hysteresis = 20.0;
  const std::vector<ChunkId> held = p.needed({start}, radius);
  ASSERT_FALSE(held.empty());
  EXPECT_TRUE(p.toEvict(held, {start}, radius + hysteresis).empty());
  // Move by less than the hysteresis: nothing goes although some chunks left the radius.
  const PlanCentre near(15.0, 20.0);
  const auto still = p.needed({near}, radius);
  EXPECT_NE(std::set<ChunkId>(still.begin(), still.end()),
            std::set<ChunkId>(held.begin(), held.end()));
  EXPECT_TRUE(p.toEvict(held, {near}, radius + hysteresis).empty());
  // Move farther: exactly the chunks beyond radius + hysteresis go.
  const PlanCentre far(70.0, 20.0);
  const auto evicted = p.toEvict(held, {far}, radius + hysteresis);
  EXPECT_FALSE(evicted.empty());
  for (const ChunkId& id : held) {
    const bool gone = std::find(evicted.begin(), evicted.end(), id) != evicted.end();
    EXPECT_EQ(gone, p.distanceToChunk(id, far) > radius + hysteresis);
  }
  // A second centre (a pose hint) keeps its own neighbourhood.
  EXPECT_TRUE(p.toEvict(held, {far, start}, radius + hysteresis).empty());
  // No centre: everything would go (callers do not evict before they know a position).
  EXPECT_EQ(p.toEvict(held, {}, radius).size(), held.size());
}

TEST(ChunkPlanner, NoDataNoCentreNoChunk) {
  const ChunkPlanner empty(geometry(), raster(), {});
  EXPECT_TRUE(empty.needed({PlanCentre(0, 0)}, 100.0).empty());
  const ChunkPlanner p(geometry(), raster(), tileBlock(0, 1, 0, 1));
  EXPECT_TRUE(p.needed({}, 100.0).empty());
  EXPECT_TRUE(p.needed({PlanCentre(0, 0)}, -1.0).empty());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(p.needed({PlanCentre(nan, 0.0)}, 100.0).empty());
  EXPECT_TRUE(p.needed({PlanCentre(1e12, 0.0)}, 100.0).empty());
  // Far from the data: nothing.
  EXPECT_TRUE(p.needed({PlanCentre(5000.0, 0.0)}, 100.0).empty());
}

TEST(SelectCentres, Priorities) {
  PositionSources s;
  EXPECT_EQ(selectCentres(s, 10.0).source, "none");
  EXPECT_TRUE(selectCentres(s, 10.0).centres.empty());

  s.initial = PlanCentre(1, 2);
  EXPECT_EQ(selectCentres(s, 10.0).source, "initial");
  EXPECT_EQ(selectCentres(s, 10.0).centres.at(0), PlanCentre(1, 2));

  s.hint = PlanCentre(3, 4);
  s.hint_age_s = 100.0;  // old, but TF never answered: the hint is all there is
  EXPECT_EQ(selectCentres(s, 10.0).source, "pose_hint");

  s.tf = PlanCentre(5, 6);
  s.last_tf = s.tf;
  const auto tf_only = selectCentres(s, 10.0);
  EXPECT_EQ(tf_only.source, "tf");
  ASSERT_EQ(tf_only.centres.size(), 1u);
  EXPECT_EQ(tf_only.centres[0], PlanCentre(5, 6));

  s.hint_age_s = 1.0;  // a fresh hint (relocalisation) is served beside TF
  const auto both = selectCentres(s, 10.0);
  EXPECT_EQ(both.source, "tf+pose_hint");
  EXPECT_EQ(both.centres.size(), 2u);

  // TF drops out: the more recent of the last TF position and the hint.
  s.tf.reset();
  s.last_tf_age_s = 0.5;
  EXPECT_EQ(selectCentres(s, 10.0).source, "last_tf");
  s.last_tf_age_s = 5.0;
  EXPECT_EQ(selectCentres(s, 10.0).source, "pose_hint");
}

}  // namespace
}  // namespace gmm_localization
