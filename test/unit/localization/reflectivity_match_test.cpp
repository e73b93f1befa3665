// The reflectivity method (core/matching/reflectivity_scan.h, MatchProcessor with
// MatchMethod::kReflectivity) on a synthetic painted road with known ground truth: the ground
// returns are selected and levelled, the branch-and-bound equals the exhaustive search on
// them, seeded poses are recovered from offsets, and a cloud without intensity is answered
// with the reason.
#include <cmath>
#include <cstdint>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/localization/match_processor.h"
#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/matching/reflectivity_scan.h"
#include "support/search_cases.h"
#include "support/street_map.h"

namespace gmm_localization {
namespace {

double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

uint64_t mix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Intensity of the synthetic road surface at a cell: asphalt (11) with a fixed grain of
/// +-3 units per 20 cm cell, a dashed centre line (3 m dashes every 9 m), two solid edge
/// lines, a crosswalk and darker repaired patches. Every value is fixed by the cell.
double roadIntensity(const CellIndex& c, const MapGeometry& g) {
  const Eigen::Vector2d p = g.cellCenter(c);
  const uint64_t h =
      mix(static_cast<uint64_t>(c.x) * 73856093ull ^ static_cast<uint64_t>(c.y) * 19349663ull);
  double i = 11.0 + 6.0 * (static_cast<double>(h % 1000) / 1000.0 - 0.5);
  if (std::abs(p.y()) < 0.1 && std::fmod(std::abs(p.x()) + 100.0, 9.0) < 3.0) i = 110.0;
  if (std::abs(std::abs(p.y()) - 3.5) < 0.1) i = 100.0;
  if (std::abs(p.x() - 14.0) < 2.0 && std::fmod(std::abs(p.y()) + 100.0, 1.0) < 0.5) i = 105.0;
  // Through int64_t: a negative double converted to an unsigned type is undefined.
  const auto block = [](double v) {
    return static_cast<uint64_t>(static_cast<int64_t>(std::floor(v / 4.0)));
  };
  const uint64_t patch = mix(block(p.x()) * 31ull ^ block(p.y()) * 17ull);
  if (patch % 7 == 0) i -= 5.0;
  return i;
}

class ReflectivityMatchTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const MapGeometry g = testing::streetGeometry();
    GmmMap map(g);
    for (int ty = -2; ty <= 1; ++ty) {
      for (int tx = -2; tx <= 1; ++tx) {
        auto tile = std::make_shared<GmmTile>(TileId{tx, ty}, g.tile_size_cells);
        const CellIndex o = g.tileOrigin({tx, ty});
        for (int ly = 0; ly < g.tile_size_cells; ++ly) {
          for (int lx = 0; lx < g.tile_size_cells; ++lx) {
            const double v =
                layer().value(static_cast<float>(roadIntensity({o.x + lx, o.y + ly}, g)));
            tile->at(lx, ly).add({1.0f, static_cast<float>(v), 0.04f});
          }
        }
        map.insert(tile);
      }
    }
    chunks_ = std::make_unique<ChunkMap>(testing::rasterizeStreet(map));
  }
  static void TearDownTestSuite() { chunks_.reset(); }

  static ReflectivityLayerOptions layer() { return ReflectivityLayerOptions(); }

  /// A scan at `truth` (base_link on the ground): ground returns within 3-35 m with the road's
  /// intensity plus noise, and as many returns from structure 1-6 m up with any intensity
  /// (which the ground band must leave out). Points in base_link.
  static ScanInput scan(const Pose6& truth, uint32_t seed, size_t* ground_count = nullptr) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 1.5);
    const Eigen::Isometry3d t = toIsometry(truth);
    const MapGeometry& g = chunks_->geometry();
    ScanInput s;
    s.stamp_s = 1.0;
    size_t ground = 0;
    for (int k = 0; k < 12000; ++k) {
      const double r = 3.0 + 32.0 * std::sqrt(u(rng)), a = 2.0 * M_PI * u(rng);
      const bool structure = k % 2 == 1;
      Eigen::Vector3d pm = t * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.0);
      double intensity = roadIntensity(g.cellAt(pm.x(), pm.y()), g) + noise(rng);
      if (structure) {
        pm.z() = 1.0 + 5.0 * u(rng);
        intensity = 255.0 * u(rng);
      } else {
        pm.z() = 0.0;  // the flat road
        ++ground;
      }
      s.points.push_back((t.inverse() * pm).cast<float>());
      s.intensity.push_back(static_cast<float>(std::max(0.0, intensity)));
    }
    if (ground_count) *ground_count = ground;
    return s;
  }

  static Pose6 randomPose(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Pose6 p;
    p.x = 20.0 * u(rng);
    p.y = 1.5 * u(rng);
    p.yaw = (u(rng) > 0 ? 0.0 : M_PI) + 0.1 * u(rng);
    p.roll = 0.02 * u(rng);  // a cambered road tilts the vehicle
    p.pitch = 0.03 * u(rng);
    return p;
  }

  static std::unique_ptr<ChunkMap> chunks_;
};
std::unique_ptr<ChunkMap> ReflectivityMatchTest::chunks_;

TEST_F(ReflectivityMatchTest, KeepsTheLevelledGroundReturnsWithTheirIntensityAsValue) {
  std::mt19937 rng(5);
  const Pose6 truth = randomPose(rng);
  size_t ground = 0;
  const ScanInput s = scan(truth, 11, &ground);
  const PointList points =
      reflectivityPoints(s.points, s.intensity, truth.roll, truth.pitch, layer());
  // Every ground return within the range, no structure (1 m and more above the band).
  EXPECT_EQ(points.size(), ground);
  for (const Eigen::Vector3f& p : points) {
    EXPECT_LE(std::hypot(p.x(), p.y()), layer().max_range_m + 1e-3);
    EXPECT_GE(p.z(), 0.0f);
    EXPECT_LE(p.z(), layer().value(255.0f));
  }
  // Levelled: without the roll and pitch far returns of a tilted vehicle leave the band.
  Pose6 tilted = truth;
  tilted.pitch = 0.05;
  const ScanInput t = scan(tilted, 11);
  EXPECT_LT(reflectivityPoints(t.points, t.intensity, 0.0, 0.0, layer()).size(), ground * 9 / 10);
  // No intensity (or one per point missing): nothing.
  EXPECT_TRUE(reflectivityPoints(s.points, {}, 0.0, 0.0, layer()).empty());
}

TEST_F(ReflectivityMatchTest, BranchAndBoundEqualsTheExhaustiveSearchOnReflectivityPoints) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RegistrationOptions bnb = reflectivityRegistrationOptions(RegistrationOptions());
  // The global search's score floor is the height likelihood's: none for reflectivity.
  EXPECT_FALSE(bnb.global.min_score_per_point > -1e300);
  RegistrationOptions exhaustive = bnb;
  exhaustive.exhaustive = true;
  for (int c = 0; c < 8; ++c) {
    const Pose6 truth = randomPose(rng);
    const ScanInput s = scan(truth, 300 + c);
    const PointList points =
        reflectivityPoints(s.points, s.intensity, truth.roll, truth.pitch, layer());
    MatchRequest request;
    request.prior = truth;
    request.prior.x += 0.8 * u(rng);
    request.prior.y += 0.8 * u(rng);
    request.prior.yaw += 0.02 * u(rng);
    request.prior.z = request.prior.roll = request.prior.pitch = 0.0;
    request.half_x_m = request.half_y_m = 1.0;
    request.half_heading_rad = 0.035;
    const auto a = Registration(bnb).match(*chunks_, points, request);
    const auto b = Registration(exhaustive).match(*chunks_, points, request);
    ASSERT_TRUE(a.ok() && b.ok()) << a.error() << " / " << b.error();
    testing::expectSame(a->search, b->search, c);
  }
}

TEST_F(ReflectivityMatchTest, RecoversSeededPosesAndLeavesHeightAndTiltToThePrior) {
  MatchMethodOptions method;
  method.method = MatchMethod::kReflectivity;
  auto processor =
      MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions(), method);
  ASSERT_TRUE(processor.ok()) << processor.error();
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst_xy = 0.0, worst_yaw = 0.0;
  for (int c = 0; c < 20; ++c) {
    const Pose6 truth = randomPose(rng);
    Prior prior;
    prior.source = PriorSource::kEkf;
    // 3 sigma: a window of +-1.8 m and +-4.5 deg, holding the offsets below.
    prior.covariance_xyh = Eigen::Vector3d(0.36, 0.36, 0.00069).asDiagonal();
    prior.pose = truth;
    prior.pose.x += 1.5 * u(rng);
    prior.pose.y += 1.5 * u(rng);
    prior.pose.yaw += 0.04 * u(rng);
    prior.pose.z = 0.05;  // the prior's height and tilt are kept as they are
    const MatchReport r = processor->process(*chunks_, scan(truth, 900 + c), prior, nullptr, false);
    ASSERT_TRUE(r.has_result) << "case " << c << ": " << r.reason;
    const double exy = std::hypot(r.result.pose.x - truth.x, r.result.pose.y - truth.y);
    const double eyaw = std::abs(angleDiff(r.result.pose.yaw, truth.yaw));
    worst_xy = std::max(worst_xy, exy);
    worst_yaw = std::max(worst_yaw, eyaw);
    EXPECT_LE(exy, 0.05) << "case " << c;
    EXPECT_LE(eyaw, 0.2 * M_PI / 180.0) << "case " << c;
    EXPECT_EQ(r.result.pose.z, prior.pose.z) << "case " << c;
    EXPECT_EQ(r.result.pose.roll, prior.pose.roll) << "case " << c;
    EXPECT_EQ(r.result.pose.pitch, prior.pose.pitch) << "case " << c;
    EXPECT_TRUE(r.result.obstacles.label.empty()) << "no obstacle labels from intensities";
  }
  std::printf("reflectivity: worst refined error over 20 poses %.4f m, %.4f deg\n", worst_xy,
              worst_yaw * 180.0 / M_PI);
}

TEST_F(ReflectivityMatchTest, ACloudWithoutIntensityIsAnsweredWithTheReason) {
  MatchMethodOptions method;
  method.method = MatchMethod::kReflectivity;
  auto processor =
      MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions(), method);
  ASSERT_TRUE(processor.ok()) << processor.error();
  std::mt19937 rng(3);
  const Pose6 truth = randomPose(rng);
  ScanInput s = scan(truth, 1);
  s.intensity.clear();
  Prior prior;
  prior.source = PriorSource::kEkf;
  prior.pose = truth;
  const MatchReport r = processor->process(*chunks_, s, prior, nullptr, false);
  EXPECT_EQ(r.outcome, MatchOutcome::kSkipped);
  EXPECT_NE(r.reason.find("no intensity field"), std::string::npos) << r.reason;
  // Invalid method options are refused, naming the key.
  method.reflectivity.metres_per_unit = 0.0;
  auto bad = MatchProcessor::create(RegistrationOptions(), LocalizationPolicyOptions(), method);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("reflectivity/metres_per_unit"), std::string::npos) << bad.error();
}

}  // namespace
}  // namespace gmm_localization
