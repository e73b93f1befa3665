// The start sweep: window centres against brute-force coverage of random tile layouts (seeded),
// the chunks of a window against every chunk near it, and the sequence of a sweep.
#include "gmm_localization/core/localization/start_sweep.h"

#include <algorithm>
#include <random>
#include <set>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

using Kind = StartSweep::Action::Kind;
using State = StartSweep::State;

/// Random tiles of a 64 m map: a random walk of tiles (a route) plus scattered ones.
std::vector<TileId> randomTiles(std::mt19937& rng) {
  std::uniform_int_distribution<int> step(-1, 1), n(1, 40), coin(0, 1), far(-12, 12);
  std::set<TileId> tiles;
  TileId t{0, 0};
  const int length = n(rng);
  for (int i = 0; i < length; ++i) {
    tiles.insert(t);
    if (coin(rng)) {
      t.x += step(rng);
    } else {
      t.y += step(rng);
    }
  }
  if (coin(rng)) tiles.insert({far(rng), far(rng)});
  return {tiles.begin(), tiles.end()};
}

/// The smallest, over the windows, of p's largest per-axis distance from a window's centre.
double bestChebyshev(const std::vector<Eigen::Vector2d>& centres, const Eigen::Vector2d& p) {
  double best = 1e300;
  for (const auto& c : centres) best = std::min(best, (p - c).cwiseAbs().maxCoeff());
  return best;
}

TEST(SweepWindowCentres, EveryPointOfEveryTileIsInsideAWindowByHalfTheOverlap) {
  std::mt19937 rng(11);
  MapGeometry g;
  g.origin_x_m = -13.0;
  g.origin_y_m = 7.5;
  for (int trial = 0; trial < 200; ++trial) {
    StartSweepOptions o;
    o.window_half_xy_m = std::uniform_real_distribution<double>(20.0, 120.0)(rng);
    o.overlap_m = std::uniform_real_distribution<double>(0.0, 0.5 * o.window_half_xy_m)(rng);
    const auto tiles = tileSquares(g, randomTiles(rng));
    const auto centres = sweepWindowCentres(tiles, o);
    ASSERT_FALSE(centres.empty());
    const double h = o.window_half_xy_m, m = 0.5 * o.overlap_m;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (const auto& t : tiles) {
      // the corners and random points
      std::vector<Eigen::Vector2d> points = {
          t.min(), t.max(), {t.min().x(), t.max().y()}, {t.max().x(), t.min().y()}};
      for (int i = 0; i < 20; ++i) {
        points.push_back(t.min() +
                         (t.max() - t.min()).cwiseProduct(Eigen::Vector2d(u(rng), u(rng))));
      }
      for (const auto& p : points) {
        ASSERT_LE(bestChebyshev(centres, p), h - m + 1e-9)
            << "trial " << trial << " point (" << p.transpose() << ")";
      }
    }
    // Every window overlaps a tile, and none is sent twice.
    for (size_t i = 0; i < centres.size(); ++i) {
      const Eigen::AlignedBox2d w(centres[i] - Eigen::Vector2d::Constant(h),
                                  centres[i] + Eigen::Vector2d::Constant(h));
      EXPECT_TRUE(std::any_of(tiles.begin(), tiles.end(),
                              [&](const auto& t) { return !w.intersection(t).isEmpty(); }));
      for (size_t j = 0; j < i; ++j) EXPECT_GT((centres[i] - centres[j]).norm(), 1e-6);
    }
  }
}

TEST(SweepWindowCentres, NearestTheTilesCentroidFirst) {
  MapGeometry g;
  std::vector<TileId> ids;
  for (int x = 0; x < 5; ++x) {
    for (int y = -1; y < 5; ++y) ids.push_back({x, y});  // the rostest fixture's 320 x 384 m
  }
  const auto tiles = tileSquares(g, ids);
  StartSweepOptions o;  // +-50 m windows, 10 m overlap
  const auto centres = sweepWindowCentres(tiles, o);
  // x: 45 .. 275 in 4, y: -19 .. 275 in 5 (spacing <= 90 m)
  ASSERT_EQ(centres.size(), 20u);
  const Eigen::Vector2d centroid(160.0, 128.0);
  for (size_t i = 1; i < centres.size(); ++i) {
    EXPECT_LE((centres[i - 1] - centroid).norm(), (centres[i] - centroid).norm() + 1e-9);
  }
  EXPECT_NEAR((centres[0] - centroid).norm(), 115.0 / 3.0, 1e-9);
}

TEST(SweepWindowCentres, AMapSmallerThanAWindowIsOneWindowAtItsCentre) {
  MapGeometry g;
  const auto centres = sweepWindowCentres(tileSquares(g, {{0, 0}}), StartSweepOptions{});
  ASSERT_EQ(centres.size(), 1u);
  EXPECT_NEAR(centres[0].x(), 32.0, 1e-9);
  EXPECT_NEAR(centres[0].y(), 32.0, 1e-9);
  EXPECT_TRUE(sweepWindowCentres({}, StartSweepOptions{}).empty());
}

TEST(SweepWindowCentres, ARoughFixSweepsOnlyTheDiscNearestFirst) {
  MapGeometry g;
  std::vector<TileId> ids;
  for (int x = 0; x < 30; ++x) ids.push_back({x, 0});  // a 1.9 km straight road
  const auto tiles = tileSquares(g, ids);
  StartSweepOptions o;
  o.region_x_m = 1000.0;
  o.region_y_m = 30.0;
  o.region_radius_m = 150.0;
  const auto centres = sweepWindowCentres(tiles, o);
  ASSERT_FALSE(centres.empty());
  EXPECT_LE(centres.size(), 4u);
  const Eigen::Vector2d fix(1000.0, 30.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-150.0, 150.0);
  for (int i = 0; i < 500; ++i) {  // every tile point within the disc is covered
    const Eigen::Vector2d p = fix + Eigen::Vector2d(u(rng), u(rng));
    if ((p - fix).norm() > 150.0 || p.y() < 0.0 || p.y() > 64.0) continue;
    EXPECT_LE(bestChebyshev(centres, p), o.window_half_xy_m - 0.5 * o.overlap_m + 1e-9);
  }
  for (size_t i = 1; i < centres.size(); ++i) {
    EXPECT_LE((centres[i - 1] - fix).norm(), (centres[i] - fix).norm() + 1e-9);
  }
  o.region_x_m = 5000.0;  // no tile within the disc
  EXPECT_TRUE(sweepWindowCentres(tiles, o).empty());
}

TEST(WindowChunks, AreTheChunksWithDataOverlappingTheWindowAgainstEveryChunkNearIt) {
  MapGeometry g;
  g.origin_x_m = 3.3;
  g.origin_y_m = -7.1;
  RasterOptions r;  // 128-cell (25.6 m) chunks
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const auto ids = randomTiles(rng);
    const ChunkPlanner planner(g, r, ids);
    std::uniform_real_distribution<double> u(-100.0, 300.0);
    const Eigen::Vector2d c(u(rng), u(rng));
    const double half = 50.0;
    const auto got = windowChunks(planner, c, half);
    const std::set<ChunkId> chosen(got.begin(), got.end());
    EXPECT_EQ(chosen.size(), got.size());
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
    const double e = planner.chunkEdgeM();
    for (int cx = -40; cx < 40; ++cx) {
      for (int cy = -40; cy < 40; ++cy) {
        const ChunkId id{cx, cy};
        const Eigen::Vector2d lo = planner.chunkMin(id);
        const bool overlap = lo.x() < c.x() + half && lo.x() + e > c.x() - half &&
                             lo.y() < c.y() + half && lo.y() + e > c.y() - half;
        EXPECT_EQ(chosen.count(id) == 1, overlap && planner.hasData(id))
            << "chunk " << cx << "," << cy << " trial " << trial;
      }
    }
  }
}

/// An answer of the matcher; global ones centred on window `window` of sweepOf's.
StartSweep::Answer answer(bool accepted, bool no_prior, bool global, int window = 0) {
  StartSweep::Answer a;
  a.accepted = accepted;
  a.no_prior = no_prior;
  a.global_search = global;
  a.window_centre = Eigen::Vector2d(100.0 * window, 0.0);
  return a;
}

StartSweep sweepOf(int windows, StartSweepOptions o = {}) {
  StartSweep s(o);
  std::vector<Eigen::Vector2d> c;
  for (int i = 0; i < windows; ++i) c.emplace_back(100.0 * i, 0.0);
  s.setWindows(c);
  return s;
}

TEST(StartSweep, WaitsForAnswersWithoutAPriorThenLoadsAndSearchesTheFirstWindow) {
  StartSweep s = sweepOf(3);                        // wait 5 s, map wait 10 s
  EXPECT_EQ(s.poll(0.0, false).kind, Kind::kNone);  // no answer yet: the matcher may be down
  s.onStatus(1.0, answer(false, true, false));
  EXPECT_EQ(s.poll(5.9, false).kind, Kind::kNone);
  s.onStatus(3.0,
             answer(false, false, false));  // a prior came (a configured pose): the wait restarts
  s.onStatus(4.0, answer(false, true, false));
  EXPECT_EQ(s.poll(8.9, false).kind, Kind::kNone);
  const auto load = s.poll(9.0, false);
  ASSERT_EQ(load.kind, Kind::kLoadMap);
  EXPECT_EQ(load.window, 0);
  EXPECT_EQ(s.state(), State::kLoading);
  EXPECT_EQ(s.poll(9.5, false).kind, Kind::kNone);  // the chunks are not there yet
  const auto search = s.poll(10.0, true);
  ASSERT_EQ(search.kind, Kind::kSearch);
  EXPECT_EQ(search.window, 0);
  EXPECT_EQ(search.centre.x(), 0.0);
  EXPECT_EQ(s.searchedEarly(), 0u);
}

TEST(StartSweep, ARejectedGlobalAnswerOrATimeoutMovesOnThenTheSweepStartsOverUpToMaxSweeps) {
  StartSweepOptions o;
  o.wait_s = 0.0;
  o.map_wait_s = 2.0;
  o.attempt_timeout_s = 20.0;
  o.max_sweeps = 2;
  StartSweep s = sweepOf(2, o);
  s.onStatus(0.0, answer(false, true, false));
  ASSERT_EQ(s.poll(0.0, false).kind, Kind::kLoadMap);
  ASSERT_EQ(s.poll(2.0, false).kind, Kind::kSearch);  // map_wait_s elapsed: searched anyway
  EXPECT_EQ(s.searchedEarly(), 1u);
  s.onStatus(2.5, answer(false, false, false));  // an interim answer (not global): still searching
  EXPECT_EQ(s.poll(2.6, true).kind, Kind::kNone);
  // The matcher's own global search around another window (still running when the pose came).
  s.onStatus(3.0, answer(false, false, true, 1));
  EXPECT_EQ(s.poll(3.0, true).kind, Kind::kNone);
  StartSweep::Answer moved = answer(false, false, true);  // the window's, moved 10 m by the INS
  moved.window_centre = Eigen::Vector2d(6.0, 8.0);
  s.onStatus(4.0, moved);  // the global search found nothing certified
  auto a = s.poll(4.0, true);
  ASSERT_EQ(a.kind, Kind::kLoadMap);
  EXPECT_EQ(a.window, 1);
  ASSERT_EQ(s.poll(4.1, true).kind, Kind::kSearch);
  EXPECT_EQ(s.poll(24.0, true).kind, Kind::kNone);
  a = s.poll(24.1, true);  // no answer in attempt_timeout_s: the first window again
  ASSERT_EQ(a.kind, Kind::kLoadMap);
  EXPECT_EQ(a.window, 0);
  EXPECT_EQ(s.sweeps(), 1);
  EXPECT_EQ(s.timedOut(), 1u);
  ASSERT_EQ(s.poll(24.2, true).kind, Kind::kSearch);
  s.onStatus(25.0, answer(false, false, true));
  ASSERT_EQ(s.poll(25.0, true).kind, Kind::kLoadMap);
  ASSERT_EQ(s.poll(25.1, true).kind, Kind::kSearch);
  s.onStatus(26.0, answer(false, false, true, 1));
  EXPECT_EQ(s.poll(26.0, true).kind, Kind::kNone);
  EXPECT_EQ(s.state(), State::kGaveUp);
  EXPECT_EQ(s.searched(), 4u);
  s.onStatus(27.0, answer(true, false, true));  // too late to matter to the sweep
  EXPECT_EQ(s.state(), State::kGaveUp);
}

TEST(StartSweep, AnAcceptedMatchEndsItAndAPoseFromSomeoneElseStandsItDown) {
  StartSweepOptions o;
  o.wait_s = 0.0;
  StartSweep s = sweepOf(4, o);
  s.onStatus(0.0, answer(false, true, false));
  ASSERT_EQ(s.poll(0.0, true).kind, Kind::kLoadMap);
  ASSERT_EQ(s.poll(0.1, true).kind, Kind::kSearch);
  s.onStatus(1.0, answer(true, false, true));
  EXPECT_EQ(s.state(), State::kLocalized);
  EXPECT_EQ(s.poll(100.0, true).kind, Kind::kNone);
  s.onExternalPose();  // localized stays localized
  EXPECT_EQ(s.state(), State::kLocalized);

  StartSweep t = sweepOf(4, o);
  t.onStatus(0.0, answer(false, true, false));
  ASSERT_EQ(t.poll(0.0, false).kind, Kind::kLoadMap);
  t.onExternalPose();
  EXPECT_EQ(t.state(), State::kStoodDown);
  EXPECT_EQ(t.poll(100.0, true).kind, Kind::kNone);

  StartSweep u = sweepOf(0, o);  // no window (no map yet): nothing to do
  u.onStatus(0.0, answer(false, true, false));
  EXPECT_EQ(u.poll(10.0, true).kind, Kind::kNone);
  EXPECT_EQ(u.state(), State::kWaiting);
}

TEST(StartSweep, ANewMapRestartsTheSweepFromItsFirstWindow) {
  StartSweepOptions o;
  o.wait_s = 1.0;
  StartSweep s = sweepOf(3, o);
  s.onStatus(0.0, answer(false, true, false));
  ASSERT_EQ(s.poll(1.0, true).kind, Kind::kLoadMap);
  ASSERT_EQ(s.poll(1.1, true).kind, Kind::kSearch);
  s.setWindows({{5.0, 5.0}});
  EXPECT_EQ(s.state(), State::kWaiting);
  EXPECT_EQ(s.poll(1.2, true).kind, Kind::kNone);  // the wait starts again
  s.onStatus(2.0, answer(false, true, false));
  const auto a = s.poll(3.0, true);
  ASSERT_EQ(a.kind, Kind::kLoadMap);
  EXPECT_EQ(a.centre, Eigen::Vector2d(5.0, 5.0));
}

TEST(StartSweepOptions, RefusesWhatCannotWork) {
  StartSweepOptions o;
  EXPECT_EQ(o.validate(), "");
  o.overlap_m = o.window_half_xy_m;
  EXPECT_NE(o.validate(), "");
  o = {};
  o.window_half_xy_m = NAN;
  EXPECT_NE(o.validate(), "");
  o = {};
  o.region_radius_m = -1.0;
  EXPECT_NE(o.validate(), "");
  o = {};
  o.max_sweeps = -1;
  EXPECT_NE(o.validate(), "");
  o = {};
  o.attempt_timeout_s = 0.0;
  EXPECT_NE(o.validate(), "");
}

}  // namespace
}  // namespace gmm_localization
