// Recovery of known poses from synthetic scans of a synthetic map (paper Algorithm 1), the
// search covariance's shape, obstacle labels and input handling.

#include "gmm_localization/core/matching/registration.h"

#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "gmm_localization/core/raster/rasterizer.h"
#include "support/corridor_map.h"
#include "support/street_fixture.h"

namespace gmm_localization {
namespace {

double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

using RegistrationTest = testing::StreetFixture;

TEST_F(RegistrationTest, RecoversFiftySeededPoses) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RegistrationOptions options;
  const Registration reg(options);
  const double res = chunks_->geometry().resolution_m;
  double worst_xy = 0.0, worst_yaw = 0.0;
  for (int c = 0; c < 50; ++c) {
    const Pose6 truth = world_->streetPose(rng);
    const PointList scan = world_->scan(truth, 35.0, 0.25, 0.0, 100 + c);
    MatchRequest req;
    req.prior = truth;
    req.prior.x += 1.8 * u(rng);
    req.prior.y += 1.8 * u(rng);
    req.prior.yaw += 0.05 * u(rng);
    req.half_x_m = req.half_y_m = 2.0;
    req.half_heading_rad = 0.0524;  // 3 degrees
    auto r = reg.match(*chunks_, scan, req);
    ASSERT_TRUE(r.ok()) << "case " << c << ": " << r.error();
    const SearchOutcome& s = r->search;
    EXPECT_LE(std::abs(s.pose.x - truth.x), res) << "case " << c;
    EXPECT_LE(std::abs(s.pose.y - truth.y), res) << "case " << c;
    EXPECT_LE(std::abs(angleDiff(s.pose.yaw, truth.yaw)), options.heading_step_rad) << "case " << c;
    const double exy = std::hypot(r->pose.x - truth.x, r->pose.y - truth.y);
    const double eyaw = std::abs(angleDiff(r->pose.yaw, truth.yaw));
    worst_xy = std::max(worst_xy, exy);
    worst_yaw = std::max(worst_yaw, eyaw);
    EXPECT_LE(exy, 0.03) << "case " << c;
    EXPECT_LE(eyaw, 0.1 * M_PI / 180.0) << "case " << c;
    EXPECT_LE(std::abs(r->pose.z - truth.z), 0.03) << "case " << c;
  }
  std::printf("worst refined error over 50 poses: %.4f m, %.4f deg\n", worst_xy,
              worst_yaw * 180.0 / M_PI);
}

TEST_F(RegistrationTest, OnAnyThreadCountTheSameResultBitForBit) {
  // Every stage on a pool (per-heading rotation, search, refinement, covariance, certificate,
  // labels) gives the one-thread result exactly, from tracking and wide windows.
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RegistrationOptions options;
  const Registration one(options);
  ASSERT_EQ(one.pool(), nullptr);
  options.threads = 2;
  const Registration two(options);
  options.threads = 3;
  const Registration three(options);
  ASSERT_EQ(three.pool()->threads(), 3);
  for (int c = 0; c < 6; ++c) {
    const Pose6 truth = world_->streetPose(rng);
    // Dense: the labels run in several blocks of points.
    const PointList scan = world_->scan(truth, 35.0, 0.1, 0.0, 300 + c);
    ASSERT_GE(scan.size(), 20000u);
    MatchRequest req;
    req.prior = truth;
    req.prior.x += 1.5 * u(rng);
    req.prior.y += 1.5 * u(rng);
    req.prior.yaw += 0.04 * u(rng);
    req.half_x_m = req.half_y_m = c % 2 ? 2.0 : 6.0;
    req.half_heading_rad = c % 2 ? 0.0524 : 0.15;
    const auto a = one.match(*chunks_, scan, req);
    ASSERT_TRUE(a.ok()) << a.error();
    for (const Registration* reg : {&two, &three}) {
      const auto b = reg->match(*chunks_, scan, req);
      ASSERT_TRUE(b.ok()) << b.error();
      EXPECT_EQ(a->search.heading_index, b->search.heading_index) << "case " << c;
      EXPECT_EQ(a->search.tx, b->search.tx) << "case " << c;
      EXPECT_EQ(a->search.ty, b->search.ty) << "case " << c;
      EXPECT_EQ(a->search.score, b->search.score) << "case " << c;
      EXPECT_EQ(a->pose.x, b->pose.x) << "case " << c;
      EXPECT_EQ(a->pose.y, b->pose.y) << "case " << c;
      EXPECT_EQ(a->pose.z, b->pose.z) << "case " << c;
      EXPECT_EQ(a->pose.roll, b->pose.roll) << "case " << c;
      EXPECT_EQ(a->pose.pitch, b->pose.pitch) << "case " << c;
      EXPECT_EQ(a->pose.yaw, b->pose.yaw) << "case " << c;
      EXPECT_EQ(a->refinement.score, b->refinement.score) << "case " << c;
      EXPECT_EQ(a->refinement.evaluations, b->refinement.evaluations) << "case " << c;
      EXPECT_TRUE(a->covariance_xyh == b->covariance_xyh) << "case " << c;
      EXPECT_EQ(a->certificate.certified, b->certificate.certified) << "case " << c;
      EXPECT_EQ(a->certificate.evaluations, b->certificate.evaluations) << "case " << c;
      EXPECT_EQ(a->certificate.protection_xy_m, b->certificate.protection_xy_m) << "case " << c;
      EXPECT_EQ(a->certificate.separation_per_point, b->certificate.separation_per_point);
      EXPECT_EQ(a->filtered.points.size(), b->filtered.points.size()) << "case " << c;
      EXPECT_EQ(a->filtered.voxels.size(), b->filtered.voxels.size()) << "case " << c;
      EXPECT_EQ(a->obstacles.obstacles, b->obstacles.obstacles) << "case " << c;
      EXPECT_EQ(a->obstacles.label, b->obstacles.label) << "case " << c;
      EXPECT_EQ(a->log_likelihood_per_point, b->log_likelihood_per_point) << "case " << c;
    }
  }
}

TEST_F(RegistrationTest, TheGlobalSearchRunsOnItsOwnPoolWithTheSameResult) {
  // global.threads differs from threads: the global search and its certificate get a pool of
  // their own; the same count shares the match's pool; the optimum is the same either way.
  RegistrationOptions options;
  const Registration one(options);
  EXPECT_EQ(one.globalPool(), nullptr);
  options.global.threads = 2;
  const Registration global_two(options);
  EXPECT_EQ(global_two.pool(), nullptr);
  ASSERT_NE(global_two.globalPool(), nullptr);
  EXPECT_EQ(global_two.globalPool()->threads(), 2);
  options.threads = 2;
  const Registration both_two(options);
  EXPECT_EQ(both_two.globalPool(), both_two.pool());
  std::mt19937 rng(78);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int c = 0; c < 2; ++c) {
    const Pose6 truth = world_->streetPose(rng);
    const PointList scan = world_->scan(truth, 35.0, 0.2, 0.0, 400 + c);
    MatchRequest req;
    req.prior = truth;
    req.prior.x += 3.0 * u(rng);
    req.prior.y += 3.0 * u(rng);
    req.prior.yaw += 2.0 * u(rng);
    req.half_x_m = req.half_y_m = 6.0;
    req.half_heading_rad = M_PI;
    const auto a = one.match(*chunks_, scan, req);
    const auto b = global_two.match(*chunks_, scan, req);
    ASSERT_TRUE(a.ok()) << a.error();
    ASSERT_TRUE(b.ok()) << b.error();
    EXPECT_TRUE(a->global) << "case " << c;
    EXPECT_EQ(a->search.score, b->search.score) << "case " << c;
    EXPECT_EQ(a->pose.x, b->pose.x) << "case " << c;
    EXPECT_EQ(a->pose.y, b->pose.y) << "case " << c;
    EXPECT_EQ(a->pose.yaw, b->pose.yaw) << "case " << c;
    EXPECT_EQ(a->global_certificate.certified, b->global_certificate.certified) << "case " << c;
    EXPECT_LE(std::hypot(a->pose.x - truth.x, a->pose.y - truth.y), 0.1) << "case " << c;
  }
}

TEST(RegistrationOptionsThreads, OutOfRangeIsRejectedWithTheRange) {
  RegistrationOptions o;
  o.threads = -1;
  EXPECT_NE(o.validate().find("threads"), std::string::npos);
  o.threads = TaskPool::kMaxThreads + 1;
  EXPECT_NE(o.validate().find("threads"), std::string::npos);
  o.threads = 0;
  EXPECT_EQ(o.validate(), "");
}

TEST(RegistrationCovariance, LargerAlongACorridorThanAcrossIt) {
  const ChunkMap chunks = testing::corridorChunks();
  const PointList scan = testing::corridorScan();
  MatchRequest req;
  req.half_x_m = req.half_y_m = 2.0;
  req.half_heading_rad = 0.05;
  auto r = Registration(RegistrationOptions()).match(chunks, scan, req);
  ASSERT_TRUE(r.ok()) << r.error();
  const Eigen::Matrix3d& c = r->covariance_xyh;
  std::printf("corridor sigma x %.3f m, y %.3f m, yaw %.4f rad\n", std::sqrt(c(0, 0)),
              std::sqrt(c(1, 1)), std::sqrt(c(2, 2)));
  EXPECT_GT(c(0, 0), 10.0 * c(1, 1));
  EXPECT_LT(std::abs(r->pose.y), 0.03);
  // Positive definite and symmetric.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  EXPECT_TRUE(c.isApprox(c.transpose()));
}

TEST_F(RegistrationTest, ThinnedCovarianceTracksTheFullOne) {
  // The covariance on every 4th prepared point against the one on all of them: the tempered
  // distribution scales with the points scored, so the two agree to within sampling noise.
  std::mt19937 rng(77);
  const Registration reg{RegistrationOptions()};
  CovarianceOptions all, thin;
  all.max_points = 0;
  double lo = 1e9, hi = 0.0, floor_share = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Pose6 truth = world_->streetPose(rng);
    const PointList scan = world_->scan(truth, 35.0, 0.25, 0.0, 300 + c);
    MatchRequest req;
    req.prior = truth;
    req.half_x_m = req.half_y_m = 2.0;
    req.half_heading_rad = 0.0524;
    auto prepared = reg.prepare(*chunks_, scan, req);
    ASSERT_TRUE(prepared.ok()) << prepared.error();
    const SearchProblem& problem = prepared->problem;
    const SearchOutcome best = branchAndBoundSearch(problem, BranchAndBoundOptions());
    thin.max_points = problem.points(best.heading_index).size() / 4;
    ASSERT_GE(thin.max_points, 100u) << "case " << c;
    const MatchCovariance a = searchCovariance(problem, best, all);
    const MatchCovariance b = searchCovariance(problem, best, thin);
    for (int k = 0; k < 3; ++k) {
      const double ratio = std::sqrt(b.covariance(k, k) / a.covariance(k, k));
      lo = std::min(lo, ratio);
      hi = std::max(hi, ratio);
      const double floor_sd = k < 2 ? all.min_sigma_xy_m : all.min_sigma_yaw_rad;
      floor_share += std::sqrt(a.covariance(k, k)) < 1.01 * floor_sd ? 1.0 / 24 : 0.0;
      EXPECT_GT(ratio, 0.67) << "case " << c << " axis " << k;
      EXPECT_LT(ratio, 1.5) << "case " << c << " axis " << k;
    }
  }
  std::printf("thinned / full sigma: %.3f .. %.3f; %.0f%% of the sigmas at their floor\n", lo, hi,
              100.0 * floor_share);
  EXPECT_LT(floor_share, 0.5);  // the comparison must be about estimated spreads, not floors
}

TEST_F(RegistrationTest, DropsNonFinitePointsAndRejectsEmptyOrOffMapScans) {
  std::mt19937 rng(5);
  const Pose6 truth = world_->streetPose(rng);
  PointList scan = world_->scan(truth, 30.0, 0.3, 0.0, 1);
  const size_t n = scan.size();
  for (size_t i = 0; i < n; i += 10) scan[i].x() = std::numeric_limits<float>::quiet_NaN();
  scan.emplace_back(std::numeric_limits<float>::infinity(), 0.f, 0.f);
  MatchRequest req;
  req.prior = truth;
  req.half_x_m = req.half_y_m = 1.0;
  req.half_heading_rad = 0.02;
  const Registration reg{RegistrationOptions()};
  auto r = reg.match(*chunks_, scan, req);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->filtered.dropped_nonfinite, (n + 9) / 10 + 1);
  EXPECT_LT(std::hypot(r->pose.x - truth.x, r->pose.y - truth.y), 0.05);

  PointList nans(1000, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  auto none = reg.match(*chunks_, nans, req);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().find("no points left"), std::string::npos) << none.error();
  EXPECT_FALSE(reg.match(*chunks_, {}, req).ok());

  MatchRequest far = req;
  far.prior.x += 10000.0;
  auto off = reg.match(*chunks_, scan, far);
  ASSERT_FALSE(off.ok());
  EXPECT_NE(off.error().find("off the map"), std::string::npos) << off.error();

  MatchRequest bad = req;
  bad.prior.yaw = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(reg.match(*chunks_, scan, bad).ok());
}

TEST_F(RegistrationTest, LabelsPointsAwayFromTheMapAsObstacles) {
  std::mt19937 rng(8);
  const Pose6 truth = world_->streetPose(rng);
  PointList scan = world_->scan(truth, 30.0, 0.3, 0.0, 2);
  const size_t map_points = scan.size();
  // A "car" 1.5 m tall, 6 m ahead, not in the map.
  for (double x = 5.0; x < 7.0; x += 0.1) {
    for (double z = 0.3; z < 1.5; z += 0.1) scan.emplace_back(x, 0.f, z);
  }
  const ObstacleLabels labels = classifyObstacles(*chunks_, scan, truth, ObstacleOptions());
  ASSERT_EQ(labels.label.size(), scan.size());
  size_t car_obstacles = 0, map_obstacles = 0;
  for (size_t i = 0; i < scan.size(); ++i) {
    const bool obstacle = labels.label[i] == PointClass::kObstacle;
    (i < map_points ? map_obstacles : car_obstacles) += obstacle ? 1 : 0;
  }
  EXPECT_GT(car_obstacles, 0.9 * (scan.size() - map_points));
  EXPECT_LT(map_obstacles, 0.05 * map_points);
}

}  // namespace
}  // namespace gmm_localization
