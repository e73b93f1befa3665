// The match certificate against brute force (every pose of the window scored), on seeded random
// maps and scans: certified exactly when the brute-force plausible set lies inside the exclusion
// zone and off the window's border, with the same protection level and separation; and on the
// synthetic street (certified from its own scans) against a corridor (never certified).

#include "gmm_localization/core/matching/match_certificate.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/corridor_map.h"
#include "support/random_chunk_map.h"
#include "support/random_map.h"
#include "support/street_map.h"
#include "support/synthetic_world.h"

namespace gmm_localization {
namespace {

/// The certificate's definition, evaluated over every pose of the window.
struct Reference {
  bool certified = false;
  bool ambiguous = false;
  bool border = false;
  bool rival_within_depth = false;
  int64_t rival = -1;  ///< best score elsewhere (-1: nothing elsewhere)
  double protection_xy_m = 0.0;
  double protection_heading_rad = 0.0;
};

Reference bruteForce(const SearchProblem& p, const SearchOutcome& opt,
                     const CertificateOptions& o) {
  const SearchWindow& w = p.window();
  const double res = p.map().geometry().resolution_m;
  const ScoreQuantizer q(p.map().options());
  const double to_units = static_cast<double>(p.scanPoints()) / q.step();
  const int64_t margin = static_cast<int64_t>(std::floor(o.margin_per_point * to_units));
  const int64_t depth = static_cast<int64_t>(std::floor(o.separation_depth_per_point * to_units));
  Reference r;
  std::vector<int64_t> scores;
  for (int j = 0; j < w.sizeH(); ++j) {
    p.scoreBlock(j, 0, 0, w.sizeX(), w.sizeY(), scores);
    for (int ty = 0; ty < w.sizeY(); ++ty) {
      for (int tx = 0; tx < w.sizeX(); ++tx) {
        const int64_t s = scores[static_cast<size_t>(ty) * w.sizeX() + tx];
        const double dxy = std::hypot((tx - opt.tx) * res, (ty - opt.ty) * res);
        const double dh = std::abs(j - opt.heading_index) * w.heading_step_rad;
        const bool elsewhere = dxy > o.exclusion_radius_m || dh > o.exclusion_heading_rad;
        if (elsewhere) r.rival = std::max(r.rival, s);
        if (s < opt.score - margin) continue;
        r.protection_xy_m = std::max(r.protection_xy_m, dxy);
        r.protection_heading_rad = std::max(r.protection_heading_rad, dh);
        r.ambiguous = r.ambiguous || elsewhere;
        r.border = r.border || (w.sizeX() > 1 && (tx == 0 || tx == w.sizeX() - 1)) ||
                   (w.sizeY() > 1 && (ty == 0 || ty == w.sizeY() - 1)) ||
                   (w.sizeH() > 1 && (j == 0 || j == w.sizeH() - 1));
      }
    }
  }
  r.rival_within_depth = r.rival >= 0 && r.rival >= opt.score - depth;
  r.certified = !r.ambiguous && !r.border;
  return r;
}

RasterOptions randomRasterOptions() {
  RasterOptions ro;
  ro.chunk_shift = 5;
  ro.num_layers = 4;
  return ro;
}

/// When the search kept its branched nodes' children (SearchOutcome::branched): checks that
/// they are the problem's scores and that the proof reading them equals the one scoring them
/// itself, evaluation count included, and returns true.
bool sameWithoutTheSearchsBranches(const SearchProblem& problem, const SearchOutcome& opt,
                                   const CertificateOptions& o, const MatchCertificate& cert,
                                   int c) {
  if (opt.branched.empty()) return false;
  for (const SearchOutcome::Branched& b : opt.branched) {
    const int j = static_cast<int>(b.key >> 48), layer = static_cast<int>((b.key >> 32) & 0xffff);
    const int ty = static_cast<int>((b.key >> 16) & 0xffff), tx = static_cast<int>(b.key & 0xffff);
    int64_t quad[4];
    problem.scoreQuad(j, layer, tx, ty, 1 << layer, quad);
    EXPECT_TRUE(std::equal(quad, quad + 4, b.scores)) << "case " << c;
    EXPECT_EQ(opt.childScores(j, layer, tx, ty), b.scores) << "case " << c;
  }
  SearchOutcome unbranched = opt;
  unbranched.branched.clear();
  const MatchCertificate alone = certifyOptimum(problem, unbranched, o);
  EXPECT_EQ(alone.failure, cert.failure) << "case " << c;
  EXPECT_EQ(alone.evaluations, cert.evaluations) << "case " << c;
  EXPECT_EQ(alone.protection_xy_m, cert.protection_xy_m) << "case " << c;
  EXPECT_EQ(alone.protection_heading_rad, cert.protection_heading_rad) << "case " << c;
  EXPECT_EQ(alone.separation_per_point, cert.separation_per_point) << "case " << c;
  return true;
}

TEST(MatchCertificate, EqualsBruteForceOnRandomCases) {
  const GmmMap map = testing::randomMap(11, testing::randomMapGeometry(), -2, -2, 4, 4, 0.35);
  const RasterOptions ro = randomRasterOptions();
  const ChunkMap chunks = testing::rasterizeRandomMap(map, ro);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int certified = 0, ambiguous = 0, edge = 0, exact_separation = 0, with_branched = 0;
  for (int c = 0; c < 120; ++c) {
    Pose6 prior;
    prior.x = -8.0 + 16.0 * u(rng);
    prior.y = -8.0 + 16.0 * u(rng);
    prior.yaw = 6.28 * u(rng);
    const SearchWindow w = SearchWindow::fromExtent(prior, 0.6 + 2.0 * u(rng), 0.6 + 2.0 * u(rng),
                                                    0.1 * u(rng), 0.02, 0.2);
    PointList pts;
    const int n = 20 + static_cast<int>(400 * u(rng));
    for (int i = 0; i < n; ++i) {
      pts.emplace_back(static_cast<float>(8.0 * u(rng) - 4.0),
                       static_cast<float>(8.0 * u(rng) - 4.0),
                       static_cast<float>(-1.8 + 5.8 * u(rng)));
    }
    auto problem = SearchProblem::create(chunks, pts, w);
    ASSERT_TRUE(problem.ok()) << problem.error();
    // Odd cases certify an exhaustive optimum (the certificate scores the coarsest layer
    // itself), even ones a branch-and-bound optimum (its coarsest-layer scores reused).
    const SearchOutcome opt =
        c % 2 ? exhaustiveSearch(problem.value()) : branchAndBoundSearch(problem.value());
    ASSERT_EQ(opt.top_scores.empty(), c % 2 == 1);
    CertificateOptions o;
    o.exclusion_radius_m = 0.2 + 0.8 * u(rng);
    o.exclusion_heading_rad = 0.01 + 0.05 * u(rng);
    o.margin_per_point = ((c / 2) % 4) * 0.02;
    o.separation_depth_per_point = o.margin_per_point + 0.1 * u(rng);
    o.max_evaluations = 1000000;
    const MatchCertificate cert = certifyOptimum(problem.value(), opt, o);
    const Reference ref = bruteForce(problem.value(), opt, o);
    with_branched += sameWithoutTheSearchsBranches(problem.value(), opt, o, cert, c) ? 1 : 0;
    ASSERT_EQ(cert.certified, ref.certified)
        << "case " << c << " failure " << certificateFailureName(cert.failure);
    EXPECT_EQ(cert.separation_exact, ref.rival_within_depth) << "case " << c;
    if (ref.rival_within_depth) {
      const double expect = static_cast<double>(opt.score - ref.rival) * ScoreQuantizer(ro).step() /
                            problem->scanPoints();
      EXPECT_NEAR(cert.separation_per_point, expect, 1e-12) << "case " << c;
      ++exact_separation;
    } else {
      EXPECT_GE(cert.separation_per_point, o.separation_depth_per_point - ScoreQuantizer(ro).step())
          << "case " << c;
    }
    if (ref.ambiguous) {
      EXPECT_EQ(cert.failure, CertificateFailure::kAmbiguous) << "case " << c;
      ++ambiguous;
    } else {
      // Not stopped early: the whole plausible set was placed.
      EXPECT_DOUBLE_EQ(cert.protection_xy_m, ref.protection_xy_m) << "case " << c;
      EXPECT_DOUBLE_EQ(cert.protection_heading_rad, ref.protection_heading_rad) << "case " << c;
      EXPECT_EQ(cert.failure,
                ref.border ? CertificateFailure::kWindowEdge : CertificateFailure::kNone)
          << "case " << c;
      edge += ref.border ? 1 : 0;
      certified += ref.certified ? 1 : 0;
    }
  }
  // Every branch of the definition was exercised.
  EXPECT_GE(certified, 10);
  EXPECT_GE(ambiguous, 10);
  EXPECT_GE(edge, 3);
  EXPECT_GE(exact_separation, 10);
  EXPECT_GE(with_branched, 20);
  std::printf(
      "certified %d, ambiguous %d, window edge %d, exact separation %d, search's branches "
      "reused %d of 120\n",
      certified, ambiguous, edge, exact_separation, with_branched);
}

TEST(MatchCertificate, ABudgetTooSmallNeverCertifiesWhatBruteForceRejects) {
  const GmmMap map = testing::randomMap(12, testing::randomMapGeometry(), -2, -2, 4, 4, 0.35);
  const RasterOptions ro = randomRasterOptions();
  const ChunkMap chunks = testing::rasterizeRandomMap(map, ro);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int budget = 0, with_branched = 0;
  for (int c = 0; c < 40; ++c) {
    Pose6 prior;
    prior.x = -6.0 + 12.0 * u(rng);
    prior.y = -6.0 + 12.0 * u(rng);
    const SearchWindow w = SearchWindow::fromExtent(prior, 2.0, 2.0, 0.06, 0.02, 0.2);
    PointList pts;
    for (int i = 0; i < 200; ++i) {
      pts.emplace_back(static_cast<float>(8.0 * u(rng) - 4.0),
                       static_cast<float>(8.0 * u(rng) - 4.0),
                       static_cast<float>(-1.8 + 5.8 * u(rng)));
    }
    auto problem = SearchProblem::create(chunks, pts, w);
    ASSERT_TRUE(problem.ok());
    const SearchOutcome opt = branchAndBoundSearch(problem.value());
    CertificateOptions o;
    o.margin_per_point = 0.02 * (c % 3);
    o.max_evaluations = 1 + c * 5;
    const MatchCertificate cert = certifyOptimum(problem.value(), opt, o);
    const Reference ref = bruteForce(problem.value(), opt, o);
    with_branched += sameWithoutTheSearchsBranches(problem.value(), opt, o, cert, c) ? 1 : 0;
    if (cert.certified) {
      EXPECT_TRUE(ref.certified) << "case " << c;
    }
    budget += cert.failure == CertificateFailure::kBudget ? 1 : 0;
  }
  EXPECT_GT(budget, 10) << "the small budgets stop most proofs";
  EXPECT_GE(with_branched, 20);
}

TEST(MatchCertificate, DisabledReportsDisabled) {
  const GmmMap map = testing::randomMap(13, testing::randomMapGeometry(), 0, 0, 1, 1);
  RasterOptions ro;
  ro.chunk_shift = 5;
  ro.num_layers = 3;
  ChunkMap chunks(map.geometry(), ro);
  chunks.insert(rasterizeChunk(map, {0, 0}, ro).value());
  PointList pts = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.5f, 0.2f}};
  Pose6 prior;
  prior.x = -2.0;
  prior.y = 4.5;
  auto problem =
      SearchProblem::create(chunks, pts, SearchWindow::fromExtent(prior, 1, 1, 0, 0.02, 0.2));
  ASSERT_TRUE(problem.ok()) << problem.error();
  CertificateOptions o;
  o.enabled = false;
  const MatchCertificate cert =
      certifyOptimum(problem.value(), exhaustiveSearch(problem.value()), o);
  EXPECT_FALSE(cert.certified);
  EXPECT_EQ(cert.failure, CertificateFailure::kDisabled);
  EXPECT_EQ(cert.evaluations, 0);
  CertificateOptions bad;
  bad.separation_depth_per_point = bad.margin_per_point / 2;
  EXPECT_FALSE(bad.validate().empty());
  EXPECT_TRUE(CertificateOptions().validate().empty());
}

TEST(MatchCertificate, StreetScansAreCertifiedNearTheTruth) {
  const testing::SyntheticWorld world(42);
  const GmmMap gmm = world.buildMap(testing::streetGeometry(), 1);
  const ChunkMap chunks = testing::rasterizeStreet(gmm);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Registration reg{RegistrationOptions()};
  int certified = 0;
  for (int c = 0; c < 10; ++c) {
    const Pose6 truth = world.streetPose(rng);
    const PointList scan = world.scan(truth, 35.0, 0.25, 0.0, 300 + c);
    MatchRequest req;
    req.prior = truth;
    req.prior.x += 1.5 * u(rng);
    req.prior.y += 1.5 * u(rng);
    req.half_x_m = req.half_y_m = 2.5;
    req.half_heading_rad = 0.0524;
    auto prepared = reg.prepare(chunks, scan, req);
    ASSERT_TRUE(prepared.ok()) << prepared.error();
    const SearchOutcome opt = branchAndBoundSearch(prepared->problem);
    const MatchCertificate cert = certifyOptimum(prepared->problem, opt, CertificateOptions());
    if (!cert.certified) continue;
    ++certified;
    // The truth lies within the protection level (plus one cell) of the optimum.
    EXPECT_LE(std::hypot(opt.pose.x - truth.x, opt.pose.y - truth.y), cert.protection_xy_m + 0.2)
        << "case " << c;
    EXPECT_LT(cert.evaluations, opt.stats.evaluations * 2) << "case " << c;
  }
  EXPECT_GE(certified, 9);
}

TEST(MatchCertificate, ACorridorIsNeverCertified) {
  // Ground everywhere and two walls along x: every translation along x scores the same.
  const ChunkMap chunks = testing::corridorChunks();
  const PointList scan = testing::corridorScan();
  MatchRequest req;
  req.half_x_m = req.half_y_m = 2.0;
  req.half_heading_rad = 0.05;
  const Registration reg{RegistrationOptions()};
  auto prepared = reg.prepare(chunks, scan, req);
  ASSERT_TRUE(prepared.ok()) << prepared.error();
  const SearchOutcome opt = branchAndBoundSearch(prepared->problem);
  const MatchCertificate cert = certifyOptimum(prepared->problem, opt, CertificateOptions());
  EXPECT_FALSE(cert.certified);
  EXPECT_NE(cert.failure, CertificateFailure::kNone);
  EXPECT_LT(cert.separation_per_point, CertificateOptions().margin_per_point + 1e-9);
}

TEST(MatchCertificate, WideWindowsGetTheWideBudget) {
  // The tracking window keeps max_evaluations; the wide window after an initial pose or a
  // relocalization (12.5 m) gets wide_max_evaluations, from wide_min_half_xy_m on, in x or y.
  CertificateOptions o;
  o.max_evaluations = 3000;
  o.wide_max_evaluations = 30000;
  o.wide_min_half_xy_m = 5.0;
  EXPECT_EQ(o.budgetFor(1.5, 1.5), 3000);
  EXPECT_EQ(o.budgetFor(4.99, 4.99), 3000);
  EXPECT_EQ(o.budgetFor(5.0, 1.0), 30000);
  EXPECT_EQ(o.budgetFor(1.0, 12.5), 30000);
  EXPECT_TRUE(o.validate().empty()) << o.validate();
  o.wide_max_evaluations = 0;
  EXPECT_NE(o.validate().find("wide_max_evaluations"), std::string::npos);
  o.wide_max_evaluations = 30000;
  o.wide_min_half_xy_m = 0.0;
  EXPECT_NE(o.validate().find("wide_min_half_xy_m"), std::string::npos);
}

}  // namespace
}  // namespace gmm_localization
