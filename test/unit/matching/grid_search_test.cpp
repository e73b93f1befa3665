// Branch-and-bound equals exhaustive (pose and score) on seeded random cases, including ties
// and windows that straddle chunk and tile borders (DESIGN.md 4.7).

#include "gmm_localization/core/matching/grid_search.h"

#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/raster/rasterizer.h"
#include "support/random_chunk_map.h"
#include "support/random_map.h"
#include "support/search_cases.h"

namespace gmm_localization {
namespace {

using testing::expectSame;
using testing::randomWindow;

TEST(GridSearch, BranchAndBoundEqualsExhaustiveOnRandomCases) {
  const GmmMap map = testing::randomMap(5, testing::randomMapGeometry(), -2, -2, 4, 4, 0.35);
  for (int coarsen : {0, 1, 2}) {
    RasterOptions o;
    o.chunk_shift = 5;
    o.num_layers = 4;
    o.z_coarsening_period = coarsen;
    const ChunkMap chunks = testing::rasterizeRandomMap(map, o);
    std::mt19937 rng(100 + coarsen);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int c = 0; c < 60; ++c) {
      // Windows straddle tile (8 m) and chunk (6.4 m) borders.
      const SearchWindow w = randomWindow(rng, 12.0, 1.0, 0.4, 2.6, 0.1);
      const PointList pts = testing::randomPoints(rng, 5 + static_cast<int>(300 * u(rng)), 4.0);
      auto problem = SearchProblem::create(chunks, pts, w);
      ASSERT_TRUE(problem.ok()) << problem.error();
      const SearchOutcome ex = exhaustiveSearch(problem.value());
      BranchAndBoundOptions bo;
      bo.prior_as_incumbent = (c % 2) == 0;
      const SearchOutcome bb = branchAndBoundSearch(problem.value(), bo);
      expectSame(ex, bb, c);
      // The prior, when used as incumbent, is the one extra base-layer evaluation.
      EXPECT_LE(bb.stats.evaluations_per_layer[0], w.poses() + (bo.prior_as_incumbent ? 1 : 0));
    }
  }
}

TEST(GridSearch, BranchAndBoundEqualsExhaustiveWithChunksMissing) {
  // A loaded region with holes: a coarse block starting in a missing chunk can still reach
  // mapped cells of a loaded neighbour, so its bound must not read the floor there.
  // Isolated mapped cells (97% empty) and a few far points: an optimum then hinges on one cell.
  const GmmMap map = testing::randomMap(21, testing::randomMapGeometry(), -2, -2, 4, 4, 0.97);
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 4;
  const ChunkMap full = testing::rasterizeRandomMap(map, o);
  std::mt19937 rng(400);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0;
  for (int c = 0; c < 150; ++c) {
    const ChunkMap chunks = testing::withoutSomeChunks(full, 500 + c, 0.4);
    const SearchWindow w = randomWindow(rng, 12.0, 1.0, 0.4, 2.6, 0.1);
    const PointList pts = testing::randomPoints(rng, 1 + static_cast<int>(4 * u(rng)), 7.0);
    auto problem = SearchProblem::create(chunks, pts, w);
    if (!problem.ok()) continue;  // every chunk under this window dropped
    ++compared;
    expectSame(exhaustiveSearch(problem.value()), branchAndBoundSearch(problem.value()), c);
  }
  EXPECT_GE(compared, 100);
}

TEST(GridSearch, BranchAndBoundEqualsExhaustiveWhenTheTopLayerIsCapped) {
  // Few layers: the coarsest layer tiles the window with many nodes (odd counts included),
  // scored four at a time.
  const GmmMap map = testing::randomMap(6, testing::randomMapGeometry(), -2, -2, 4, 4, 0.35);
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 2;
  const ChunkMap chunks = testing::rasterizeRandomMap(map, o);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int c = 0; c < 30; ++c) {
    const SearchWindow w = randomWindow(rng, 10.0, 0.0, 1.0, 2.0, 0.05);
    const PointList pts = testing::randomPoints(rng, 20 + static_cast<int>(200 * u(rng)), 4.0);
    auto problem = SearchProblem::create(chunks, pts, w);
    ASSERT_TRUE(problem.ok()) << problem.error();
    ASSERT_EQ(problem->topLayer(), 2);
    const SearchOutcome ex = exhaustiveSearch(problem.value());
    std::vector<TraversalNode> traversal;
    const SearchOutcome bb = branchAndBoundSearch(problem.value(), {c % 2 == 0}, &traversal);
    expectSame(ex, bb, c);
    // Every bound the search used, the coarsest layer's four-at-a-time ones included, is the
    // node's own score.
    for (const TraversalNode& n : traversal) {
      ASSERT_EQ(n.bound, problem->score(n.heading_index, n.layer, n.tx, n.ty))
          << "case " << c << ", layer " << n.layer << " node (" << n.tx << ", " << n.ty << ")";
    }
    const int64_t top_nodes = ((w.sizeX() + 3) / 4) * ((w.sizeY() + 3) / 4) * w.sizeH();
    EXPECT_GT(top_nodes, 4 * w.sizeH()) << "case " << c << ": more than a 2 x 2 top grid";
    EXPECT_EQ(bb.stats.evaluations_per_layer[2], top_nodes) << "case " << c;
  }
}

TEST(GridSearch, TiesResolveIdenticallyOnAUniformMap) {
  // Every cell holds the same mixture: all translations of a heading tie exactly.
  MapGeometry g = testing::randomMapGeometry();
  GmmMap map(g);
  for (int ty = -2; ty < 2; ++ty) {
    for (int tx = -2; tx < 2; ++tx) {
      auto tile = std::make_shared<GmmTile>(TileId{tx, ty}, g.tile_size_cells);
      for (auto& cell : tile->cells()) cell.add({1.0f, 0.0f, 0.05f});
      map.insert(tile);
    }
  }
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 4;
  const ChunkMap chunks = testing::rasterizeRandomMap(map, o);
  TaskPool pool(3);
  std::mt19937 rng(9);
  for (int c = 0; c < 40; ++c) {
    Pose6 prior;
    prior.x = -3.0 + 0.17 * c;
    prior.y = 1.0 - 0.05 * c;
    PointList pts;
    for (int i = 0; i < 30; ++i) pts.emplace_back(0.3f * i - 4.0f, 0.1f * (i % 7), 0.0f);
    const SearchWindow w = SearchWindow::fromExtent(prior, 1.6, 1.2, 0.06, 0.02, 0.2);
    auto problem = SearchProblem::create(chunks, pts, w);
    ASSERT_TRUE(problem.ok());
    const SearchOutcome ex = exhaustiveSearch(problem.value());
    const SearchOutcome bb = branchAndBoundSearch(problem.value(), {false});
    expectSame(ex, bb, c);
    EXPECT_EQ(ex.tx + ex.ty + ex.heading_index, 0) << "ties go to the smallest key";
    // Also when the passes of a pool each find a tied leaf of their own headings.
    expectSame(ex, branchAndBoundSearch(problem.value(), {false}, nullptr, &pool), c);
  }
}

TEST(GridSearch, OffMapScanIsRejectedWithReason) {
  const GmmMap map = testing::randomMap(5, testing::randomMapGeometry(), 0, 0, 1, 1);
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 3;
  ChunkMap chunks(map.geometry(), o);
  chunks.insert(rasterizeChunk(map, {0, 0}, o).value());
  Pose6 far;
  far.x = 5000.0;
  std::mt19937 rng(1);
  auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 50, 3.0),
                                       SearchWindow::fromExtent(far, 2.0, 2.0, 0.0, 0.01, 0.2));
  ASSERT_FALSE(problem.ok());
  EXPECT_NE(problem.error().find("off the map"), std::string::npos) << problem.error();
  auto empty = SearchProblem::create(chunks, {}, SearchWindow::fromExtent({}, 1, 1, 0, 0.01, 0.2));
  ASSERT_FALSE(empty.ok());
}

}  // namespace
}  // namespace gmm_localization
