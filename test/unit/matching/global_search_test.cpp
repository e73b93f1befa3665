// The global branch-and-bound over heading intervals equals the exhaustive search (pose and
// score, ties included) on seeded random cases over the full turn, also with chunks missing and
// root blocks coarser than the map's coarsest layer; a score floor keeps that optimum when it
// reaches the floor and proves that nothing does otherwise; and every interval bound is at least
// the best leaf below it (brute force).

#include "gmm_localization/core/matching/global_search.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "support/full_turn_cases.h"

namespace gmm_localization {
namespace {

using testing::fullTurnWindow;

/// The score floor off (testing::withoutScoreFloor).
constexpr double kFloorOff = -std::numeric_limits<double>::infinity();

/// Brute force: the best exact score of the leaves of node (j0, hl, layer, tx, ty).
int64_t bestLeaf(const SearchProblem& problem, int j0, int hl, int layer, int tx, int ty) {
  const SearchWindow& w = problem.window();
  int64_t best = 0;
  for (int j = j0; j < std::min(j0 + (1 << hl), w.sizeH()); ++j) {
    for (int y = ty; y < std::min(ty + (1 << layer), w.sizeY()); ++y) {
      for (int x = tx; x < std::min(tx + (1 << layer), w.sizeX()); ++x) {
        best = std::max(best, problem.score(j, 0, x, y));
      }
    }
  }
  return best;
}

void expectSame(const SearchOutcome& ex, const GlobalSearchOutcome& g, int c) {
  EXPECT_TRUE(g.complete) << "case " << c;
  EXPECT_EQ(ex.score, g.best.score) << "case " << c;
  EXPECT_EQ(ex.heading_index, g.best.heading_index) << "case " << c;
  EXPECT_EQ(ex.tx, g.best.tx) << "case " << c;
  EXPECT_EQ(ex.ty, g.best.ty) << "case " << c;
}

TEST(GlobalSearch, EqualsExhaustiveOverTheFullTurnOnRandomCases) {
  TaskPool pool(2);
  int cases = 0;
  for (int coarsen : {0, 2}) {
    // Also a map of isolated cells with a few far points: optima then hinge on a swing.
    const bool sparse = coarsen == 0;
    const ChunkMap full = testing::smallRandomChunks(7, sparse ? 0.97 : 0.8, coarsen);
    std::mt19937 rng(300 + coarsen);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int c = 0; c < 30; ++c, ++cases) {
      const ChunkMap chunks = testing::withoutSomeChunks(full, 40 + c, c % 3 == 0 ? 0.3 : 0.0);
      const SearchWindow w = fullTurnWindow(rng, 10.0);
      const PointList pts =
          sparse ? testing::randomPoints(rng, 1 + static_cast<int>(4 * u(rng)), 7.0)
                 : testing::randomPoints(rng, 20 + static_cast<int>(200 * u(rng)), 5.0);
      auto problem = SearchProblem::create(chunks, pts, w);
      if (!problem.ok()) continue;  // every chunk under this window dropped
      const SearchOutcome ex = exhaustiveSearch(problem.value());
      GlobalSearchOptions go;
      go.min_score_per_point = kFloorOff;  // the optimum however low (the floor: below)
      go.root_heading_levels = c % 6;
      go.root_layer = c % 4 == 1 ? 6 : -1;  // 6 > num_layers: several reads per point
      go.prior_as_incumbent = (c % 2) == 0;
      go.heading_split_share = c % 5 == 0 ? 4.0 : 0.5;
      go.max_reads_per_point = std::array<int, 4>{1, 2, 4, 16}[c % 4];
      // One queue, several in turn on one thread, several in parallel.
      go.queues = c % 4;  // 0: one per thread of the pool
      expectSame(ex, globalBranchAndBound(problem.value(), go, c % 2 == 0 ? &pool : nullptr), c);
    }
  }
  EXPECT_GE(cases, 40);
}

TEST(GlobalSearch, OnAPoolTheSameOptimumAsOneQueue) {
  // The queues on two threads against one queue on one: the same leaf. Cheap (no exhaustive
  // search), so that the sanitizers' thread pass runs it (scripts/run_sanitizers.sh).
  TaskPool pool(2);
  const ChunkMap chunks = testing::smallRandomChunks(29, 0.8);
  std::mt19937 rng(31);
  int cases = 0;
  for (int c = 0; c < 12; ++c) {
    const SearchWindow w = fullTurnWindow(rng, 10.0);
    auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 150, 5.0), w);
    if (!problem.ok()) continue;
    GlobalSearchOptions one;
    one.queues = 1;
    one.min_score_per_point = kFloorOff;
    const GlobalSearchOutcome a = globalBranchAndBound(problem.value(), one);
    ASSERT_TRUE(a.complete) << "case " << c;
    GlobalSearchOptions per_thread;  // queues 0: one per thread of the pool
    per_thread.min_score_per_point = kFloorOff;
    per_thread.root_layer = c % 2 == 0 ? 2 : -1;
    const GlobalSearchOutcome b = globalBranchAndBound(problem.value(), per_thread, &pool);
    expectSame(a.best, b, c);
    ++cases;
  }
  EXPECT_GE(cases, 8);
}

TEST(GlobalSearch, EqualScoresInSeveralQueuesGiveTheExhaustiveTieBreak) {
  // One or two points over a map of isolated cells: many poses share the best score, spread
  // over roots of different queues. Queues run in turn here (no pool), so a later queue always
  // meets an incumbent equal to its own best and must not stop at it.
  const ChunkMap chunks = testing::smallRandomChunks(17, 0.95, 0);
  std::mt19937 rng(23);
  int cases = 0, tied = 0;
  for (int c = 0; c < 40; ++c) {
    const SearchWindow w = fullTurnWindow(rng, 8.0);
    auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 1 + c % 2, 4.0), w);
    if (!problem.ok()) continue;
    const SearchOutcome ex = exhaustiveSearch(problem.value());
    int64_t best_count = 0;  // leaves with the best score
    for (int j = 0; j < w.sizeH(); ++j) {
      for (int y = 0; y < w.sizeY(); ++y) {
        for (int x = 0; x < w.sizeX(); ++x) best_count += problem->score(j, 0, x, y) == ex.score;
      }
    }
    tied += best_count > 1;
    for (int queues : {2, 3, 5}) {
      GlobalSearchOptions go;
      go.min_score_per_point = kFloorOff;
      go.queues = queues;
      go.root_heading_levels = 2;
      go.root_layer = 2;  // many roots, so that equal leaves fall in different queues
      expectSame(ex, globalBranchAndBound(problem.value(), go), c * 10 + queues);
      ++cases;
    }
  }
  EXPECT_GE(cases, 90);
  EXPECT_GE(tied, 20);  // the case this test is about
}

TEST(GlobalSearch, AScoreFloorKeepsTheOptimumItReachesAndProvesTheOneItDoesNot) {
  // Floors just below, at, just above and well above the exhaustive optimum (in score units,
  // converted to nats per point as a user sets it): at or below it, the same optimum, ties
  // included; above it, no optimum and `below_floor`, never a budget stop. On one thread (the
  // node counts of parallel queues depend on timing), never more node scores than without a
  // floor, and fewer in all when the floor is well above the optimum.
  TaskPool pool(2);
  const ChunkMap chunks = testing::smallRandomChunks(13, 0.8);
  const ScoreQuantizer q(chunks.options());
  std::mt19937 rng(41);
  int cases = 0, below = 0;
  int64_t far_above = 0, far_above_without = 0;
  for (int c = 0; c < 16; ++c) {
    const SearchWindow w = fullTurnWindow(rng, 10.0);
    auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 30 + 10 * c, 5.0), w);
    if (!problem.ok()) continue;
    const SearchOutcome ex = exhaustiveSearch(problem.value());
    GlobalSearchOptions off;
    off.min_score_per_point = kFloorOff;
    off.queues = 1 + c % 3;
    off.prior_as_incumbent = c % 2 == 0;
    const GlobalSearchOutcome no_floor = globalBranchAndBound(problem.value(), off);
    expectSame(ex, no_floor, c);
    const bool parallel = c % 2 == 0;
    const double n = static_cast<double>(problem->scanPoints());
    for (double offset : {-5.5, -0.5, 0.5, 5.5}) {
      GlobalSearchOptions go = off;
      // ceil(ex.score + offset) score units: ex.score - 5, ex.score, ex.score + 1, + 6.
      go.min_score_per_point = q.floor() + (static_cast<double>(ex.score) + offset) * q.step() / n;
      ASSERT_TRUE(go.validate().empty()) << go.validate();
      const GlobalSearchOutcome g =
          globalBranchAndBound(problem.value(), go, parallel ? &pool : nullptr);
      const int k = c * 10 + static_cast<int>(offset + 6.0);
      if (offset < 0.0) {
        expectSame(ex, g, k);
        EXPECT_FALSE(g.below_floor) << "case " << k;
      } else {
        EXPECT_FALSE(g.complete) << "case " << k;
        EXPECT_TRUE(g.below_floor) << "case " << k;
        EXPECT_FALSE(g.cancelled) << "case " << k;
        EXPECT_EQ(g.best.heading_index, w.half_h) << "case " << k;  // the prior, not an optimum
        ++below;
      }
      if (!parallel) {
        EXPECT_LE(g.best.stats.evaluations, no_floor.best.stats.evaluations) << "case " << k;
        if (offset > 5.0) {
          far_above += g.best.stats.evaluations;
          far_above_without += no_floor.best.stats.evaluations;
        }
      }
      ++cases;
    }
  }
  EXPECT_GE(cases, 48);
  EXPECT_GE(below, 24);
  EXPECT_LT(far_above, far_above_without);
  GlobalSearchOptions bad;
  bad.min_score_per_point = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(bad.validate().empty());
  bad.min_score_per_point = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(bad.validate().empty());
}

TEST(GlobalSearch, IntervalBoundIsAtLeastEveryLeafBelowIt) {
  // A sparse map (92% empty cells), so that a bound missing part of a point's reach shows.
  const ChunkMap full = testing::smallRandomChunks(11, 0.92, 0);
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int64_t nodes = 0, tight = 0;
  for (int c = 0; c < 40; ++c) {
    const ChunkMap chunks = testing::withoutSomeChunks(full, 90 + c, c % 2 == 0 ? 0.25 : 0.0);
    const SearchWindow w = fullTurnWindow(rng, 10.0);
    const PointList pts = testing::randomPoints(rng, 30 + static_cast<int>(150 * u(rng)), 6.0);
    auto created = SearchProblem::create(chunks, pts, w);
    if (!created.ok()) continue;
    const SearchProblem& problem = created.value();
    for (int k = 0; k < 25; ++k, ++nodes) {
      // Mostly short intervals over small blocks (the dilation decides), some translation-only
      // blocks coarser than the map's layers (several reads per point).
      const bool coarse = k % 5 == 0;
      const int hl = coarse ? 0 : 1 + static_cast<int>(u(rng) * 3.0);
      const int layer = coarse ? 5 : static_cast<int>(u(rng) * 3.0);
      const int j0 = static_cast<int>(u(rng) * w.sizeH());
      const int tx = static_cast<int>(u(rng) * w.sizeX());
      const int ty = static_cast<int>(u(rng) * w.sizeY());
      const int64_t best = bestLeaf(problem, j0, hl, layer, tx, ty);
      for (int reads : {1, 4, 16}) {
        const int64_t b = headingIntervalBound(problem, j0, hl, layer, tx, ty, nullptr, reads);
        ASSERT_GE(b, best) << "case " << c << " node " << k << " hl " << hl << " layer " << layer
                           << " reads " << reads;
        if (b == best && reads == 4) ++tight;
      }
    }
  }
  EXPECT_GE(nodes, 800);
  EXPECT_LT(tight, nodes);  // not the exact max everywhere, or the test could not fail
}

TEST(GlobalSearch, IntervalBoundCoversTheReachOfAFarPoint) {
  // One point 4-7 m out over a map of isolated cells (97% empty): the best leaf of a heading
  // interval is the one that swings the point onto a mapped cell, often far from where the
  // middle heading puts it, so a bound that under-estimates the swing fails here.
  const ChunkMap chunks = testing::smallRandomChunks(13, 0.97, 0);
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int64_t nodes = 0, scoring = 0;
  for (int c = 0; c < 200; ++c) {
    const double r = 4.0 + 3.0 * u(rng), a = 6.28 * u(rng);
    const PointList pts = {Eigen::Vector3f(static_cast<float>(r * std::cos(a)),
                                           static_cast<float>(r * std::sin(a)),
                                           static_cast<float>(-1.0 + 3.0 * u(rng)))};
    const SearchWindow w = fullTurnWindow(rng, 10.0);
    auto created = SearchProblem::create(chunks, pts, w);
    if (!created.ok()) continue;
    const SearchProblem& problem = created.value();
    for (int k = 0; k < 10; ++k, ++nodes) {
      const int hl = 1 + static_cast<int>(u(rng) * 3.0);
      const int layer = static_cast<int>(u(rng) * 2.0);
      const int j0 = static_cast<int>(u(rng) * w.sizeH());
      const int tx = static_cast<int>(u(rng) * w.sizeX());
      const int ty = static_cast<int>(u(rng) * w.sizeY());
      const int64_t best = bestLeaf(problem, j0, hl, layer, tx, ty);
      if (best > 0) ++scoring;
      ASSERT_GE(headingIntervalBound(problem, j0, hl, layer, tx, ty), best)
          << "case " << c << " node " << k << " hl " << hl << " layer " << layer;
    }
  }
  EXPECT_GE(scoring, 150);  // enough nodes whose leaves reach a mapped cell
  EXPECT_GE(nodes, 1500);
}

TEST(GlobalSearch, LeafBoundIsTheExactScore) {
  const ChunkMap chunks = testing::smallRandomChunks(3, 0.3);
  std::mt19937 rng(5);
  const SearchWindow w = fullTurnWindow(rng, 6.0);
  auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 120, 5.0), w);
  ASSERT_TRUE(problem.ok()) << problem.error();
  for (int j = 0; j < w.sizeH(); j += 7) {
    EXPECT_EQ(headingIntervalBound(problem.value(), j, 0, 0, 3, 2),
              problem.value().score(j, 0, 3, 2));
  }
}

/// The small full-turn case the budget and cancel tests stop early: chunks, window, problem.
struct StoppedCase {
  ChunkMap chunks = testing::smallRandomChunks(9, 0.3);
  std::mt19937 rng{8};
  SearchWindow w = fullTurnWindow(rng, 6.0);
  Result<SearchProblem> problem =
      SearchProblem::create(chunks, testing::randomPoints(rng, 150, 5.0), w);
};

TEST(GlobalSearch, BudgetStopsWithoutClaimingAnOptimum) {
  StoppedCase k;
  const SearchWindow& w = k.w;
  auto& problem = k.problem;
  ASSERT_TRUE(problem.ok()) << problem.error();
  GlobalSearchOptions go;
  go.min_score_per_point = kFloorOff;
  go.max_evaluations = 5;
  const GlobalSearchOutcome g = globalBranchAndBound(problem.value(), go);
  EXPECT_FALSE(g.complete);
  EXPECT_FALSE(g.below_floor);
  EXPECT_EQ(g.best.heading_index, w.half_h);  // the prior, reported as such
  EXPECT_TRUE(go.validate().empty());
  go.root_heading_levels = 40;
  EXPECT_FALSE(go.validate().empty());
}

TEST(GlobalSearch, ACancelFlagStopsItAsItsBudgetWouldAndSaysSo) {
  StoppedCase k;
  const SearchWindow& w = k.w;
  auto& problem = k.problem;
  ASSERT_TRUE(problem.ok()) << problem.error();
  GlobalSearchOptions go;
  go.min_score_per_point = kFloorOff;  // random points: far below a real scan's optimum
  const GlobalSearchOutcome full = globalBranchAndBound(problem.value(), go);
  ASSERT_TRUE(full.complete);
  EXPECT_FALSE(full.cancelled);
  std::atomic<bool> cancel{false};
  const GlobalSearchOutcome unset = globalBranchAndBound(problem.value(), go, nullptr, &cancel);
  EXPECT_TRUE(unset.complete);  // a flag never set changes nothing
  EXPECT_EQ(unset.best.score, full.best.score);
  EXPECT_EQ(unset.best.stats.evaluations, full.best.stats.evaluations);
  cancel = true;
  const GlobalSearchOutcome g = globalBranchAndBound(problem.value(), go, nullptr, &cancel);
  EXPECT_FALSE(g.complete);
  EXPECT_TRUE(g.cancelled);
  EXPECT_FALSE(g.below_floor);
  EXPECT_EQ(g.best.heading_index, w.half_h);  // the prior, not an optimum
  EXPECT_LT(g.best.stats.evaluations, full.best.stats.evaluations);
}

}  // namespace
}  // namespace gmm_localization
