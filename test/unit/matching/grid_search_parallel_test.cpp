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

}  // namespace
}  // namespace gmm_localization
