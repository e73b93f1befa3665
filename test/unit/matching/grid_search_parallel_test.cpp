// The branch-and-bound on a task pool (one pass per thread over interleaved headings, sharing
// the best leaf score) against the exhaustive search and the one-thread search, on seeded random
// cases with ties and missing chunks; the search problem built on a pool against the serial one.
// Also run by the TSan pass (scripts/run_sanitizers.sh).

#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/matching/grid_search.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/random_chunk_map.h"
#include "support/random_map.h"
#include "support/search_cases.h"

namespace gmm_localization {
namespace {

using testing::expectSame;
using testing::randomWindow;

TEST(GridSearchParallel, OnSeveralThreadsTheSameOptimumAndTopLayer) {
  // The parallel passes share only the best leaf score: their combined result must be the
  // exhaustive optimum, ties (uniform map) and missing chunks included, for any thread count,
  // and the problem built on a pool must be the same problem.
  const GmmMap sparse = testing::randomMap(21, testing::randomMapGeometry(), -2, -2, 4, 4, 0.9);
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 4;
  const ChunkMap full = testing::rasterizeRandomMap(sparse, o);
  TaskPool two(2), three(3);
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0;
  for (int c = 0; c < 80; ++c) {
    const ChunkMap chunks = c % 2 ? testing::withoutSomeChunks(full, 900 + c, 0.3) : full;
    const SearchWindow w = randomWindow(rng, 12.0, 1.0, 0.4, 2.6, 0.1);
    const PointList pts = testing::randomPoints(rng, 1 + static_cast<int>(120 * u(rng)), 5.0);
    auto problem = SearchProblem::create(chunks, pts, w);
    if (!problem.ok()) continue;
    ++compared;
    const SearchOutcome ex = exhaustiveSearch(problem.value());
    const SearchOutcome serial = branchAndBoundSearch(problem.value(), {c % 3 != 0});
    for (TaskPool* pool : {&two, &three}) {
      auto built = SearchProblem::create(chunks, pts, w, pool);
      ASSERT_TRUE(built.ok());
      for (int j = 0; j < w.sizeH(); ++j) {
        const auto& a = problem->points(j);
        const auto& b = built->points(j);
        ASSERT_EQ(a.size(), b.size()) << "case " << c << " heading " << j;
        for (size_t i = 0; i < a.size(); ++i) {
          ASSERT_TRUE(a[i].gx == b[i].gx && a[i].gy == b[i].gy && a[i].zb == b[i].zb &&
                      a[i].count == b[i].count)
              << "case " << c << " heading " << j << " point " << i;
        }
      }
      const SearchOutcome par = branchAndBoundSearch(built.value(), {c % 3 != 0}, nullptr, pool);
      expectSame(ex, par, c);
      EXPECT_EQ(par.top_scores, serial.top_scores) << "case " << c;
      EXPECT_EQ(par.pose.x, serial.pose.x);
      EXPECT_EQ(par.pose.yaw, serial.pose.yaw);
      EXPECT_EQ(par.log_likelihood, serial.log_likelihood);
    }
  }
  EXPECT_GE(compared, 60);
}

TEST(GridSearchParallel, OnSeveralThreadsTiesGoToTheSmallestKey) {
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
  for (int c = 0; c < 20; ++c) {
    Pose6 prior;
    prior.x = -3.0 + 0.17 * c;
    prior.y = 1.0 - 0.05 * c;
    PointList pts;
    for (int i = 0; i < 30; ++i) pts.emplace_back(0.3f * i - 4.0f, 0.1f * (i % 7), 0.0f);
    const SearchWindow w = SearchWindow::fromExtent(prior, 1.6, 1.2, 0.06, 0.02, 0.2);
    auto problem = SearchProblem::create(chunks, pts, w);
    ASSERT_TRUE(problem.ok());
    const SearchOutcome bb = branchAndBoundSearch(problem.value(), {false}, nullptr, &pool);
    expectSame(exhaustiveSearch(problem.value()), bb, c);
    EXPECT_EQ(bb.tx + bb.ty + bb.heading_index, 0) << "ties go to the smallest key";
  }
}

}  // namespace
}  // namespace gmm_localization
