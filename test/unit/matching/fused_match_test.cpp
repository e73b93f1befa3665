// The fused method (core/matching/fused_channel.h, MatchMethod::kFused): the height likelihood
// of the scan plus the reflectivity likelihood of its ground returns, on a synthetic corridor
// with known ground truth. Its walls are uniform along the road (the height layer alone cannot
// tell where along it the vehicle is) and paint stripes cross the road (the reflectivity layer
// can). Checked: every node score is the sum of the two channels' scores; the node bounds are
// admissible; branch-and-bound, interval search and exhaustive search agree; seeded poses are
// recovered from tracking offsets; the height layer alone is off along the corridor where the
// fused method is not; incompatible maps and scans without intensity are refused with reasons.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/matching/global_search.h"
#include "gmm_localization/core/matching/reflectivity_scan.h"
#include "support/search_cases.h"
#include "support/street_map.h"

namespace gmm_localization {
namespace {

constexpr double kWallY = 4.0;       // inner faces of the corridor's walls at y = +-4 m
constexpr double kWallHeight = 3.0;  // [m]

double wrapDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

uint64_t hashCell(const CellIndex& c) {
  uint64_t x = static_cast<uint64_t>(c.x) * 73856093ull ^ static_cast<uint64_t>(c.y) * 19349663ull;
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Road intensity: asphalt (11) with a fixed grain of +-3 units per cell, solid edge lines at
/// y = +-3.5 m, and stripes 0.6 m wide across the road at irregular spacing. Nothing varies along
/// x but the stripes.
double roadIntensity(const CellIndex& c, const MapGeometry& g) {
  const Eigen::Vector2d p = g.cellCenter(c);
  double i = 11.0 + 6.0 * (static_cast<double>(hashCell({0, c.y}) % 1000) / 1000.0 - 0.5);
  if (std::abs(std::abs(p.y()) - 3.5) < 0.1) i = 100.0;
  static const double kStripes[] = {-44.0, -37.5, -29.0, -23.5, -14.0, -9.5, -2.0, 3.0,
                                    11.5,  15.0,  24.5,  28.0,  36.5,  41.0, 47.5};
  for (double s : kStripes) {
    if (std::abs(p.y()) < 3.4 && std::abs(p.x() - s) < 0.3) i = 105.0;
  }
  return i;
}

bool isWall(double y) { return std::abs(y) >= kWallY && std::abs(y) < kWallY + 0.4; }

class FusedMatchTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const MapGeometry g = testing::streetGeometry();
    GmmMap height(g), reflectivity(g);
    for (int ty = -2; ty <= 1; ++ty) {
      for (int tx = -2; tx <= 1; ++tx) {
        auto h = std::make_shared<GmmTile>(TileId{tx, ty}, g.tile_size_cells);
        auto r = std::make_shared<GmmTile>(TileId{tx, ty}, g.tile_size_cells);
        const CellIndex o = g.tileOrigin({tx, ty});
        for (int ly = 0; ly < g.tile_size_cells; ++ly) {
          for (int lx = 0; lx < g.tile_size_cells; ++lx) {
            const CellIndex c{o.x + lx, o.y + ly};
            const double y = g.cellCenter(c).y();
            if (std::abs(y) >= kWallY + 0.4) continue;  // behind the walls: never seen
            if (isWall(y)) {  // a wall face: heights spread over 0..3 m, the same all along x
              h->at(lx, ly).add({1.0f, 0.5f * kWallHeight, 0.75f});
              continue;
            }
            h->at(lx, ly).add({1.0f, 0.0f, 0.0025f});  // the flat road
            const double v = layer().value(static_cast<float>(roadIntensity(c, g)));
            r->at(lx, ly).add({1.0f, static_cast<float>(v), 0.04f});
          }
        }
        height.insert(h);
        reflectivity.insert(r);
      }
    }
    height_ = std::make_unique<ChunkMap>(testing::rasterizeStreet(height));
    reflectivity_ = std::make_unique<ChunkMap>(testing::rasterizeStreet(reflectivity));
  }
  static void TearDownTestSuite() {
    height_.reset();
    reflectivity_.reset();
  }

  static ReflectivityLayerOptions layer() { return ReflectivityLayerOptions(); }

  /// A scan at `truth` (base_link on the road): road returns within 3-28 m inside the
  /// corridor with the road's intensity plus noise, and wall returns 0-3 m up within 25 m
  /// along the road. base_link.
  static ScanInput scan(const Pose6& truth, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 1.5);
    const Eigen::Isometry3d t = toIsometry(truth);
    const MapGeometry& g = height_->geometry();
    ScanInput s;
    s.stamp_s = 1.0;
    while (s.points.size() < 12000) {
      const bool wall = s.points.size() % 2 == 1;
      Eigen::Vector3d pm;
      double intensity = 0.0;
      if (wall) {
        const double side = u(rng) < 0.5 ? -1.0 : 1.0;
        pm = Eigen::Vector3d(truth.x - 25.0 + 50.0 * u(rng), side * (kWallY + 0.02),
                             kWallHeight * u(rng));
        intensity = 255.0 * u(rng);
      } else {
        const double r = 3.0 + 25.0 * std::sqrt(u(rng)), a = 2.0 * M_PI * u(rng);
        pm = t * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.0);
        if (std::abs(pm.y()) >= kWallY - 0.1) continue;
        pm.z() = 0.0;
        intensity = roadIntensity(g.cellAt(pm.x(), pm.y()), g) + noise(rng);
      }
      s.points.push_back((t.inverse() * pm).cast<float>());
      s.intensity.push_back(static_cast<float>(std::max(0.0, intensity)));
    }
    return s;
  }

  static Pose6 randomPose(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Pose6 p;
    p.x = 15.0 * u(rng);  // the scan (28 m) and window stay on the +-51 m map
    p.y = 1.0 * u(rng);
    p.yaw = (u(rng) > 0 ? 0.0 : M_PI) + 0.05 * u(rng);
    p.roll = 0.01 * u(rng);
    p.pitch = 0.01 * u(rng);
    return p;
  }

  /// The fused channel of `s` seen from a prior with `truth`'s roll and pitch.
  static FusedChannel channel(const ScanInput& s, const Pose6& truth) {
    FusedChannel f;
    f.map = reflectivity_.get();
    f.points = reflectivityPoints(s.points, s.intensity, truth.roll, truth.pitch, layer());
    return f;
  }

  static std::unique_ptr<ChunkMap> height_, reflectivity_;
};
std::unique_ptr<ChunkMap> FusedMatchTest::height_;
std::unique_ptr<ChunkMap> FusedMatchTest::reflectivity_;

/// The three problems of one case: the fused one, and each channel alone.
struct Problems {
  SearchProblem fused, height, ground;
};

Problems prepare(const ChunkMap& hmap, const ChunkMap& rmap, const PointList& height_points,
                 const PointList& ground_points, const SearchWindow& w) {
  SearchWindow ground_window = w;
  ground_window.prior.z = 0.0;  // the second channel's heights are absolute
  const SecondChannel second{&rmap, &ground_points};
  auto f = SearchProblem::create(hmap, height_points, w, nullptr, &second);
  auto h = SearchProblem::create(hmap, height_points, w);
  auto g = SearchProblem::create(rmap, ground_points, ground_window);
  EXPECT_TRUE(f.ok() && h.ok() && g.ok());
  return {std::move(f.value()), std::move(h.value()), std::move(g.value())};
}

TEST_F(FusedMatchTest, EveryNodeScoresTheSumOfBothChannelsAndItsBoundIsAdmissible) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked_nodes = 0;
  for (int c = 0; c < 6; ++c) {
    const Pose6 truth = randomPose(rng);
    const ScanInput s = scan(truth, 500 + c);
    const FilteredScan f = filterScan(s.points, truth.roll, truth.pitch, ScanFilterOptions());
    const FusedChannel ground = channel(s, truth);
    const SearchWindow w =
        SearchWindow::fromExtent(truth, 1.6 + u(rng), 1.6 + u(rng), 0.03, 0.00873, 0.2);
    Problems p = prepare(*height_, *reflectivity_, f.points, ground.points, w);
    EXPECT_EQ(p.fused.numChannels(), 2);
    EXPECT_EQ(p.fused.scanPoints(), p.height.scanPoints() + p.ground.scanPoints());
    for (int k = 0; k < 40; ++k) {
      const int j = static_cast<int>(u(rng) * w.sizeH());
      const int layer = static_cast<int>(u(rng) * 4);
      const int tx = static_cast<int>(u(rng) * w.sizeX()),
                ty = static_cast<int>(u(rng) * w.sizeY());
      const int64_t node = p.fused.score(j, layer, tx, ty);
      ASSERT_EQ(node, p.height.score(j, layer, tx, ty) + p.ground.score(j, layer, tx, ty));
      // Admissible: no leaf of the node scores above it.
      const int n = 1 << layer;
      std::vector<int64_t> leaves;
      p.fused.scoreBlock(j, tx, ty, n, n, leaves);
      for (int64_t leaf : leaves) ASSERT_GE(node, leaf) << "case " << c << " layer " << layer;
      EXPECT_EQ(leaves[0], p.fused.score(j, 0, tx, ty));
      // The children of a node (scoreQuad) are the sums too, and below their parent.
      if (layer > 0) {
        int64_t quad[4], hq[4], gq[4];
        p.fused.scoreQuad(j, layer - 1, tx, ty, n / 2, quad);
        p.height.scoreQuad(j, layer - 1, tx, ty, n / 2, hq);
        p.ground.scoreQuad(j, layer - 1, tx, ty, n / 2, gq);
        for (int q = 0; q < 4; ++q) {
          ASSERT_EQ(quad[q], hq[q] + gq[q]);
          ASSERT_GE(node, quad[q]);
        }
      }
      // A heading-interval node bounds every leaf of its headings and translations.
      const int hl = static_cast<int>(u(rng) * 3);
      const int j0 = std::min(j, std::max(0, w.sizeH() - (1 << hl)));
      const int64_t interval = headingIntervalBound(p.fused, j0, hl, layer, tx, ty);
      for (int jj = j0; jj < std::min(j0 + (1 << hl), w.sizeH()); ++jj) {
        p.fused.scoreBlock(jj, tx, ty, n, n, leaves);
        for (int64_t leaf : leaves) ASSERT_GE(interval, leaf) << "case " << c;
      }
      ++checked_nodes;
    }
  }
  EXPECT_EQ(checked_nodes, 240);
}

TEST_F(FusedMatchTest, BranchAndBoundAndIntervalSearchEqualTheExhaustiveSearch) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RegistrationOptions bnb;
  RegistrationOptions exhaustive = bnb;
  exhaustive.exhaustive = true;
  for (int c = 0; c < 10; ++c) {
    const Pose6 truth = randomPose(rng);
    const ScanInput s = scan(truth, 300 + c);
    const FusedChannel ground = channel(s, truth);
    MatchRequest request;
    request.prior = truth;
    request.prior.x += 0.8 * u(rng);
    request.prior.y += 0.8 * u(rng);
    request.prior.yaw += 0.02 * u(rng);
    request.half_x_m = request.half_y_m = 1.2;
    request.half_heading_rad = 0.035;
    request.fused = &ground;
    const auto a = Registration(bnb).match(*height_, s.points, request);
    const auto b = Registration(exhaustive).match(*height_, s.points, request);
    ASSERT_TRUE(a.ok() && b.ok()) << a.error() << " / " << b.error();
    testing::expectSame(a->search, b->search, c);
    // The interval search (global localization's) over the same problem.
    auto prepared = Registration(bnb).prepare(*height_, s.points, request);
    ASSERT_TRUE(prepared.ok()) << prepared.error();
    ASSERT_EQ(prepared->problem.numChannels(), 2);
    GlobalSearchOptions global;
    global.root_heading_levels = 2;
    const GlobalSearchOutcome g = globalBranchAndBound(prepared->problem, global);
    ASSERT_TRUE(g.complete);
    testing::expectSame(g.best, exhaustiveSearch(prepared->problem), c);
    // The score floor is the height likelihood's: off for two channels, however high it is set.
    global.min_score_per_point = 100.0;
    const GlobalSearchOutcome floored = globalBranchAndBound(prepared->problem, global);
    EXPECT_TRUE(floored.complete && !floored.below_floor) << "case " << c;
    EXPECT_EQ(floored.best.score, g.best.score) << "case " << c;
  }
}

MatchReport matchFrom(const MatchProcessor& processor, const ChunkMap& height,
                      const ChunkMap* reflectivity, const ScanInput& s, const Pose6& prior_pose) {
  Prior prior;
  prior.source = PriorSource::kEkf;
  // 3 sigma: a window of +-1.8 m and +-4.5 deg, holding the offsets of the tests.
  prior.covariance_xyh = Eigen::Vector3d(0.36, 0.36, 0.00069).asDiagonal();
  prior.pose = prior_pose;
  return processor.process(height, s, prior, nullptr, false, nullptr, reflectivity);
}

MatchProcessor processorFor(MatchMethod m) {
  MatchMethodOptions method;
  method.method = m;
  auto p = MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions(), method);
  EXPECT_TRUE(p.ok()) << p.error();
  return std::move(p.value());
}

TEST_F(FusedMatchTest, RecoversSeededPosesFromTrackingOffsets) {
  const MatchProcessor processor = processorFor(MatchMethod::kFused);
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_xy = 0.0, worst_yaw = 0.0, worst_z = 0.0;
  for (int c = 0; c < 12; ++c) {
    const Pose6 truth = randomPose(rng);
    Pose6 prior = truth;
    prior.x += 1.5 * u(rng);
    prior.y += 1.5 * u(rng);
    prior.yaw += 0.04 * u(rng);
    prior.z += 0.1 * u(rng);
    const MatchReport r =
        matchFrom(processor, *height_, reflectivity_.get(), scan(truth, 900 + c), prior);
    ASSERT_TRUE(r.has_result) << "case " << c << ": " << r.reason;
    EXPECT_TRUE(r.accepted()) << "case " << c << ": " << r.reason;
    const double exy = std::hypot(r.result.pose.x - truth.x, r.result.pose.y - truth.y);
    const double eyaw = std::abs(wrapDiff(r.result.pose.yaw, truth.yaw));
    const double ez = std::abs(r.result.pose.z - truth.z);
    worst_xy = std::max(worst_xy, exy);
    worst_yaw = std::max(worst_yaw, eyaw);
    worst_z = std::max(worst_z, ez);
    EXPECT_LE(exy, 0.06) << "case " << c;
    EXPECT_LE(eyaw, 0.2 * M_PI / 180.0) << "case " << c;
    EXPECT_LE(ez, 0.03) << "case " << c << ": z is the height points' to refine";
    // Obstacle labels come from the height part: one per scan point.
    EXPECT_EQ(r.result.obstacles.label.size(), r.points.size()) << "case " << c;
  }
  std::printf("fused: worst refined error over 12 poses %.4f m, %.4f deg, z %.4f m\n", worst_xy,
              worst_yaw * 180.0 / M_PI, worst_z);
}

TEST_F(FusedMatchTest, StripesAcrossTheRoadFixWhereAlongTheCorridorTheHeightLayerCannot) {
  const MatchProcessor height_only = processorFor(MatchMethod::kHeight);
  const MatchProcessor fused = processorFor(MatchMethod::kFused);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int height_off = 0;
  for (int c = 0; c < 8; ++c) {
    const Pose6 truth = randomPose(rng);
    const ScanInput s = scan(truth, 700 + c);
    Pose6 prior = truth;
    prior.x += (c % 2 == 0 ? 1.0 : -1.0) * (0.8 + 0.4 * std::abs(u(rng)));  // along the road
    prior.y += 0.3 * u(rng);
    // The height layer alone: every pose along the corridor scores alike.
    const MatchReport h = matchFrom(height_only, *height_, nullptr, s, prior);
    ASSERT_TRUE(h.has_result) << "case " << c << ": " << h.reason;
    const SearchWindow& w = h.search_window;
    auto problem = SearchProblem::create(*height_, h.result.filtered.points, w);
    ASSERT_TRUE(problem.ok());
    const int j = h.result.search.heading_index, tx = h.result.search.tx;
    const int ty = h.result.search.ty;
    const int shifted = tx + (tx < w.half_x ? 5 : -5);
    EXPECT_EQ(problem->score(j, 0, tx, ty), problem->score(j, 0, shifted, ty))
        << "case " << c << ": the corridor should be uniform along x for the height layer";
    const double height_along = std::abs(h.result.pose.x - truth.x);
    height_off += height_along > 0.4 ? 1 : 0;
    // Fused: the stripes say where.
    const MatchReport f = matchFrom(fused, *height_, reflectivity_.get(), s, prior);
    ASSERT_TRUE(f.has_result) << "case " << c << ": " << f.reason;
    EXPECT_LE(std::abs(f.result.pose.x - truth.x), 0.06) << "case " << c;
    EXPECT_LE(std::abs(f.result.pose.y - truth.y), 0.06) << "case " << c;
    std::printf("case %d: prior %.2f m along, height alone %.2f m, fused %.3f m off along x\n", c,
                prior.x - truth.x, height_along, std::abs(f.result.pose.x - truth.x));
  }
  EXPECT_GE(height_off, 6) << "the height layer alone should be lost along the corridor";
}

TEST_F(FusedMatchTest, RefusesIncompatibleMapsAndScansWithoutIntensity) {
  const MatchProcessor processor = processorFor(MatchMethod::kFused);
  std::mt19937 rng(3);
  const Pose6 truth = randomPose(rng);
  ScanInput s = scan(truth, 1);
  // No reflectivity map given: skipped with the reason.
  MatchReport r = matchFrom(processor, *height_, nullptr, s, truth);
  EXPECT_EQ(r.outcome, MatchOutcome::kSkipped);
  EXPECT_NE(r.reason.find("no reflectivity map"), std::string::npos) << r.reason;
  // A second map of other cells: refused, naming what differs.
  MapGeometry coarse = height_->geometry();
  coarse.resolution_m = 0.4;
  const ChunkMap other(coarse, height_->options());
  EXPECT_NE(channelCompatibility(*height_, other).find("resolution"), std::string::npos);
  r = matchFrom(processor, *height_, &other, s, truth);
  EXPECT_EQ(r.outcome, MatchOutcome::kRejected);
  EXPECT_NE(r.reason.find("cannot be searched together"), std::string::npos) << r.reason;
  RasterOptions big = height_->options();
  big.chunk_shift = 8;
  EXPECT_NE(channelCompatibility(*height_, ChunkMap(height_->geometry(), big)).find("chunk"),
            std::string::npos);
  EXPECT_EQ(channelCompatibility(*height_, *reflectivity_), "");
  // No intensity: skipped, naming the method.
  s.intensity.clear();
  r = matchFrom(processor, *height_, reflectivity_.get(), s, truth);
  EXPECT_EQ(r.outcome, MatchOutcome::kSkipped);
  EXPECT_NE(r.reason.find("no intensity field: the fused method"), std::string::npos) << r.reason;
  // The method names.
  MatchMethod m = MatchMethod::kHeight;
  EXPECT_TRUE(parseMatchMethod("fused", &m));
  EXPECT_EQ(m, MatchMethod::kFused);
  EXPECT_STREQ(matchMethodName(MatchMethod::kFused), "fused");
  EXPECT_FALSE(parseMatchMethod("both", &m));
}

}  // namespace
}  // namespace gmm_localization
