// The certificate of a global optimum (global_certificate.h) against brute force over every
// pose of seeded random full-turn windows: certified exactly when every pose within the margin
// of the optimum lies inside the exclusion zone (headings compared around the circle) and off
// the translations' border, with the same protection level; the same on one queue, several in
// turn and several on a pool; a budget too small never certifies what brute force rejects.

#include "gmm_localization/core/matching/global_certificate.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "support/full_turn_cases.h"

namespace gmm_localization {
namespace {

struct Reference {
  bool ambiguous = false;
  bool border = false;
  bool across_seam = false;  ///< a plausible pose at the other end of the headings
  double protection_xy_m = 0.0;
  double protection_heading_rad = 0.0;
  CertificateFailure failure() const {
    return ambiguous ? CertificateFailure::kAmbiguous
                     : (border ? CertificateFailure::kWindowEdge : CertificateFailure::kNone);
  }
};

/// The certificate's definition over every pose of a full-turn window.
Reference bruteForce(const SearchProblem& p, const SearchOutcome& opt,
                     const CertificateOptions& o) {
  const SearchWindow& w = p.window();
  const double res = p.map().geometry().resolution_m;
  const ScoreQuantizer q(p.map().options());
  const int64_t margin = static_cast<int64_t>(
      std::floor(o.margin_per_point * static_cast<double>(p.scanPoints()) / q.step()));
  Reference r;
  for (int j = 0; j < w.sizeH(); ++j) {
    const double a =
        std::abs(std::remainder((j - opt.heading_index) * w.heading_step_rad, 2.0 * M_PI));
    for (int ty = 0; ty < w.sizeY(); ++ty) {
      for (int tx = 0; tx < w.sizeX(); ++tx) {
        if (p.score(j, 0, tx, ty) < opt.score - margin) continue;
        const double dxy = std::hypot((tx - opt.tx) * res, (ty - opt.ty) * res);
        r.protection_xy_m = std::max(r.protection_xy_m, dxy);
        r.protection_heading_rad = std::max(r.protection_heading_rad, a);
        r.ambiguous = r.ambiguous || dxy > o.exclusion_radius_m || a > o.exclusion_heading_rad;
        r.across_seam = r.across_seam || std::abs(j - opt.heading_index) > w.sizeH() / 2;
        r.border = r.border || tx == 0 || tx == w.sizeX() - 1 || ty == 0 || ty == w.sizeY() - 1;
      }
    }
  }
  return r;
}

TEST(GlobalCertificate, EqualsBruteForceOnRandomCases) {
  TaskPool pool(2);
  const ChunkMap chunks = testing::smallRandomChunks(41, 0.8);
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int cases = 0, certified = 0, ambiguous = 0, edge = 0, seam = 0;
  for (int c = 0; c < 60; ++c) {
    SearchWindow w = testing::fullTurnWindow(rng, 10.0);
    const PointList pts = testing::randomPoints(rng, 20 + static_cast<int>(150 * u(rng)), 5.0);
    auto problem = SearchProblem::create(chunks, pts, w);
    if (!problem.ok()) continue;
    GlobalSearchOptions go = testing::withoutScoreFloor();
    go.root_heading_levels = c % 6;
    go.queues = c % 3;  // 0: one per thread of the pool (or one)
    GlobalSearchOutcome g = globalBranchAndBound(problem.value(), go);
    ASSERT_TRUE(g.complete);
    if (c % 2 == 1) {
      // The window turned so that the optimum sits by the heading seam (first or last
      // heading): its neighbours in heading lie across it, at the other end.
      Pose6 prior = w.prior;
      prior.yaw = g.best.pose.yaw + (c % 4 == 1 ? -3.1 : 3.1);
      w = SearchWindow::fromExtent(prior, w.half_x * 0.2, w.half_y * 0.2, 3.1416, 0.1, 0.2);
      problem = SearchProblem::create(chunks, pts, w);
      ASSERT_TRUE(problem.ok());
      g = globalBranchAndBound(problem.value(), go);
      ASSERT_TRUE(g.complete);
      seam += g.best.heading_index <= 1 || g.best.heading_index >= w.sizeH() - 2;
    }
    CertificateOptions co;
    co.margin_per_point = std::array<double, 3>{0.0, 0.05, 0.4}[c % 3];
    co.separation_depth_per_point = co.margin_per_point;
    co.exclusion_heading_rad = c % 2 == 0 ? 0.035 : 0.25;
    co.exclusion_radius_m = c % 4 < 2 ? 0.5 : 1.5;
    co.global_max_evaluations = 1000000000;
    const MatchCertificate cert =
        certifyGlobalOptimum(problem.value(), g.best, co, go, c % 2 == 0 ? &pool : nullptr);
    const Reference ref = bruteForce(problem.value(), g.best, co);
    EXPECT_EQ(ref.failure(), cert.failure) << "case " << c;
    EXPECT_EQ(cert.failure == CertificateFailure::kNone, cert.certified) << "case " << c;
    if (c % 2 == 1) {
      // The bounds the search kept are the problem's, and on one queue the proof reading them
      // is the one computing them itself, evaluation count included.
      ASSERT_FALSE(g.best.interval_bounds.empty()) << "case " << c;
      for (size_t i = 0; i < g.best.interval_bounds.size(); i += 7) {
        const SearchOutcome::IntervalBound& b = g.best.interval_bounds[i];
        const int j0 = static_cast<int>(b.key >> 48), hl = static_cast<int>((b.key >> 40) & 0xff);
        const int layer = static_cast<int>((b.key >> 32) & 0xff);
        const int ty = static_cast<int>((b.key >> 16) & 0xffff),
                  tx = static_cast<int>(b.key & 0xffff);
        EXPECT_EQ(b.bound, headingIntervalBound(problem.value(), j0, hl, layer, tx, ty, nullptr,
                                                go.max_reads_per_point))
            << "case " << c;
      }
      SearchOutcome alone = g.best;
      alone.interval_bounds.clear();
      const MatchCertificate computed = certifyGlobalOptimum(problem.value(), alone, co, go);
      EXPECT_EQ(computed.failure, cert.failure) << "case " << c;
      EXPECT_EQ(computed.evaluations, cert.evaluations) << "case " << c;
      EXPECT_EQ(computed.protection_xy_m, cert.protection_xy_m) << "case " << c;
      EXPECT_EQ(computed.protection_heading_rad, cert.protection_heading_rad) << "case " << c;
    }
    if (cert.certified) {
      EXPECT_NEAR(ref.protection_xy_m, cert.protection_xy_m, 1e-9) << "case " << c;
      EXPECT_NEAR(ref.protection_heading_rad, cert.protection_heading_rad, 1e-9) << "case " << c;
    }
    ++cases;
    certified += cert.certified;
    ambiguous += ref.ambiguous;
    edge += ref.failure() == CertificateFailure::kWindowEdge;
  }
  EXPECT_GE(cases, 40);
  // The cases cover each outcome.
  EXPECT_GE(certified, 5);
  EXPECT_GE(ambiguous, 5);
  EXPECT_GE(edge, 2);
  EXPECT_GE(seam, 15);
}

TEST(GlobalCertificate, HeadingsAcrossTheSeamAreNeighbours) {
  // Points 1-1.5 m out: a turn of a few hundredths of a radian keeps most in their cells, so
  // the optimum's score ties with headings next to it, also across the seam of a full turn
  // (the window turned so that the optimum is by its first or last heading). Those are inside
  // the exclusion zone (2 heading steps), not elsewhere.
  const ChunkMap chunks = testing::smallRandomChunks(67, 0.5);
  std::mt19937 rng(71);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int across = 0;
  for (int c = 0; c < 40; ++c) {
    PointList pts;
    for (int i = 0; i < 30; ++i) {
      const double r = 1.0 + 0.5 * u(rng), t = 6.28 * u(rng);
      pts.emplace_back(static_cast<float>(r * std::cos(t)), static_cast<float>(r * std::sin(t)),
                       static_cast<float>(-1.0 + 3.0 * u(rng)));
    }
    SearchWindow w = testing::fullTurnWindow(rng, 10.0);
    auto problem = SearchProblem::create(chunks, pts, w);
    if (!problem.ok()) continue;
    const GlobalSearchOutcome first =
        globalBranchAndBound(problem.value(), testing::withoutScoreFloor());
    Pose6 prior = w.prior;
    prior.yaw = first.best.pose.yaw + (c % 2 == 0 ? -3.15 : 3.15);
    w = SearchWindow::fromExtent(prior, w.half_x * 0.2, w.half_y * 0.2, 3.1416, 0.1, 0.2);
    problem = SearchProblem::create(chunks, pts, w);
    ASSERT_TRUE(problem.ok());
    const GlobalSearchOutcome g =
        globalBranchAndBound(problem.value(), testing::withoutScoreFloor());
    CertificateOptions co;
    co.margin_per_point = 0.0;
    co.exclusion_heading_rad = 0.2;
    co.exclusion_radius_m = 0.3;
    const MatchCertificate cert = certifyGlobalOptimum(problem.value(), g.best, co, {});
    const Reference ref = bruteForce(problem.value(), g.best, co);
    EXPECT_EQ(ref.failure(), cert.failure) << "case " << c;
    if (cert.certified) {
      EXPECT_NEAR(ref.protection_heading_rad, cert.protection_heading_rad, 1e-9) << "case " << c;
    }
    across += ref.across_seam && ref.failure() == CertificateFailure::kNone;
  }
  EXPECT_GE(across, 2);  // certified with a plausible pose across the seam (2 of 40 here)
}

TEST(GlobalCertificate, ABudgetTooSmallNeverCertifiesWhatBruteForceRejects) {
  const ChunkMap chunks = testing::smallRandomChunks(47, 0.8);
  std::mt19937 rng(53);
  int budget_failures = 0;
  for (int c = 0; c < 30; ++c) {
    const SearchWindow w = testing::fullTurnWindow(rng, 10.0);
    auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 100, 5.0), w);
    if (!problem.ok()) continue;
    const GlobalSearchOutcome g =
        globalBranchAndBound(problem.value(), testing::withoutScoreFloor());
    CertificateOptions co;
    co.margin_per_point = 0.2;
    co.global_max_evaluations = 1 + c * 20;
    const MatchCertificate cert = certifyGlobalOptimum(problem.value(), g.best, co, {});
    const Reference ref = bruteForce(problem.value(), g.best, co);
    if (ref.failure() != CertificateFailure::kNone) EXPECT_FALSE(cert.certified) << "case " << c;
    budget_failures += cert.failure == CertificateFailure::kBudget;
  }
  EXPECT_GE(budget_failures, 5);
}

TEST(GlobalCertificate, ACancelFlagStopsTheProofUncertifiedAndSaysSo) {
  const ChunkMap chunks = testing::smallRandomChunks(67, 0.8);
  std::mt19937 rng(71);
  int cases = 0, shortened = 0;
  for (int c = 0; c < 12; ++c) {
    const SearchWindow w = testing::fullTurnWindow(rng, 10.0);
    auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 100, 5.0), w);
    if (!problem.ok()) continue;
    ++cases;
    const GlobalSearchOutcome g =
        globalBranchAndBound(problem.value(), testing::withoutScoreFloor());
    const MatchCertificate full = certifyGlobalOptimum(problem.value(), g.best, {}, {});
    std::atomic<bool> cancel{false};
    bool cancelled = true;
    const MatchCertificate unset =
        certifyGlobalOptimum(problem.value(), g.best, {}, {}, nullptr, &cancel, &cancelled);
    EXPECT_FALSE(cancelled);  // a flag never set changes nothing
    EXPECT_EQ(unset.failure, full.failure) << "case " << c;
    EXPECT_EQ(unset.evaluations, full.evaluations) << "case " << c;
    cancel = true;
    const MatchCertificate stopped =
        certifyGlobalOptimum(problem.value(), g.best, {}, {}, nullptr, &cancel, &cancelled);
    EXPECT_TRUE(cancelled) << "case " << c;
    EXPECT_FALSE(stopped.certified) << "case " << c;
    EXPECT_EQ(stopped.failure, CertificateFailure::kBudget) << "case " << c;
    EXPECT_LE(stopped.evaluations, full.evaluations) << "case " << c;
    shortened += stopped.evaluations < full.evaluations;
  }
  EXPECT_GE(cases, 8);
  EXPECT_GE(shortened, cases / 2);  // only the roots were scored before the flag was seen
}

TEST(GlobalCertificate, DisabledReportsDisabled) {
  const ChunkMap chunks = testing::smallRandomChunks(59, 0.8);
  std::mt19937 rng(61);
  auto problem = SearchProblem::create(chunks, testing::randomPoints(rng, 50, 5.0),
                                       testing::fullTurnWindow(rng, 10.0));
  ASSERT_TRUE(problem.ok());
  CertificateOptions co;
  co.enabled = false;
  const MatchCertificate cert = certifyGlobalOptimum(
      problem.value(), globalBranchAndBound(problem.value(), testing::withoutScoreFloor()).best, co,
      {});
  EXPECT_FALSE(cert.certified);
  EXPECT_EQ(CertificateFailure::kDisabled, cert.failure);
}

}  // namespace
}  // namespace gmm_localization
