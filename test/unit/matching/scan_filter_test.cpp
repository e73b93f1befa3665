// The scan filter (voxelling, ground mask, search-point selection) against brute-force
// references on seeded random clouds, and the flat key index behind it.

#include "gmm_localization/core/matching/scan_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/key_index.h"

namespace gmm_localization {
namespace {

/// Points in clusters (so that voxels hold several), with negative coordinates and points on
/// voxel faces.
PointList randomCloud(uint32_t seed, size_t n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> centre(-60.0f, 60.0f), jitter(-0.3f, 0.3f);
  PointList pts;
  while (pts.size() < n) {
    const Eigen::Vector3f c(centre(rng), centre(rng), 0.1f * centre(rng));
    for (int k = 0; k < 8; ++k)
      pts.emplace_back(c + Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng)));
    pts.emplace_back(0.4f * std::round(c.x() / 0.4f), -0.2f, 0.6f);  // exactly on faces
  }
  return pts;
}

TEST(KeyIndex, NumbersKeysInFirstSeenOrderAndGrows) {
  KeyIndex index(4);  // grows far past the expected size
  std::mt19937_64 rng(3);
  std::vector<uint64_t> keys;
  for (int i = 0; i < 5000; ++i) keys.push_back(rng() >> 1);
  keys.push_back(0);
  keys.push_back((uint64_t{1} << 63) - 1);
  for (size_t i = 0; i < keys.size(); ++i) {
    bool inserted = false;
    EXPECT_EQ(index.insert(keys[i], inserted), i);
    EXPECT_TRUE(inserted);
  }
  for (size_t i = 0; i < keys.size(); ++i) {
    bool inserted = true;
    EXPECT_EQ(index.insert(keys[i], inserted), i);
    EXPECT_FALSE(inserted);
    EXPECT_EQ(index.find(keys[i]), static_cast<int64_t>(i));
  }
  EXPECT_EQ(index.size(), keys.size());
  EXPECT_EQ(index.find(12345), -1);
}

TEST(ScanFilter, VoxelCentroidsMatchABruteForceReference) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const PointList pts = randomCloud(seed, 20000);
    const double voxel = 0.2;
    // Reference: voxels by floor(coordinate / voxel), centroids, first-seen order.
    std::map<std::tuple<int64_t, int64_t, int64_t>, size_t> slot;
    std::vector<Eigen::Vector3d> sum;
    std::vector<int> count;
    for (const Eigen::Vector3f& p : pts) {
      const auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.x() / voxel)),
                                       static_cast<int64_t>(std::floor(p.y() / voxel)),
                                       static_cast<int64_t>(std::floor(p.z() / voxel)));
      auto it = slot.emplace(key, sum.size()).first;
      if (it->second == sum.size()) {
        sum.emplace_back(Eigen::Vector3d::Zero());
        count.push_back(0);
      }
      sum[it->second] += p.cast<double>();
      ++count[it->second];
    }
    const PointList got = voxelDownsample(pts, voxel);
    ASSERT_EQ(got.size(), sum.size()) << "seed " << seed;
    for (size_t i = 0; i < got.size(); ++i) {
      const Eigen::Vector3f want = (sum[i] / count[i]).cast<float>();
      ASSERT_LT((got[i] - want).norm(), 1e-5f) << "seed " << seed << " voxel " << i;
    }
  }
}

TEST(ScanFilter, GroundMaskMatchesABruteForceReference) {
  const PointList pts = randomCloud(9, 20000);
  const double cell = 2.0, band = 0.25;
  std::map<std::pair<int64_t, int64_t>, float> lowest;
  auto key = [&](const Eigen::Vector3f& p) {
    return std::make_pair(static_cast<int64_t>(std::floor(p.x() / cell)),
                          static_cast<int64_t>(std::floor(p.y() / cell)));
  };
  for (const Eigen::Vector3f& p : pts) {
    auto it = lowest.emplace(key(p), p.z()).first;
    it->second = std::min(it->second, p.z());
  }
  const std::vector<bool> ground = groundMask(pts, cell, band);
  ASSERT_EQ(ground.size(), pts.size());
  size_t n_ground = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    EXPECT_EQ(ground[i], pts[i].z() <= lowest[key(pts[i])] + static_cast<float>(band)) << i;
    n_ground += ground[i] ? 1 : 0;
  }
  EXPECT_GT(n_ground, 0u);
  EXPECT_LT(n_ground, pts.size());
}

TEST(ScanFilter, CountsWhatItDropsAndCapsTheSearchPoints) {
  PointList pts = randomCloud(5, 30000);
  const size_t n = pts.size();
  pts.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  pts.emplace_back(0.0f, std::numeric_limits<float>::infinity(), 0.0f);
  pts.emplace_back(1.0f, 1.0f, 0.0f);    // inside the minimum range
  pts.emplace_back(500.0f, 0.0f, 0.0f);  // beyond the maximum range
  pts.emplace_back(20.0f, 0.0f, 50.0f);  // above the height band
  ScanFilterOptions o;
  o.max_points = 1500;
  const FilteredScan f = filterScan(pts, 0.0, 0.0, o);
  EXPECT_EQ(f.input_points, n + 5);
  EXPECT_EQ(f.dropped_nonfinite, 2u);
  EXPECT_GE(f.dropped_range, 2u);
  EXPECT_GE(f.dropped_height, 1u);
  EXPECT_EQ(f.points.size(), o.max_points);
  EXPECT_GT(f.voxels.size(), o.max_points);
  for (const Eigen::Vector3f& p : f.points) EXPECT_TRUE(p.allFinite());
}

/// What a sensor turning at w and moving at v (constant, in its own frame) sees at time t of a
/// point P given in its frame at the stamp: R(w t)^T (P - v t).
Eigen::Vector3f seenAt(const Eigen::Vector3d& P, double t, const Eigen::Vector3d& v,
                       const Eigen::Vector3d& w) {
  const Eigen::Vector3d rv = w * t;
  const double a = rv.norm();
  const Eigen::Matrix3d R =
      a > 0.0 ? Eigen::AngleAxisd(a, rv / a).toRotationMatrix() : Eigen::Matrix3d::Identity();
  return (R.transpose() * (P - v * t)).cast<float>();
}

TEST(Deskew, MovesEveryPointBackToWhereItWasAtTheStamp) {
  // Synthetic ground truth: points of a static scene, each seen at its own time of a
  // revolution (and of a merged four-sensor one, up to 0.18 s after the stamp and 0.1 s before)
  // by a sensor that turns and drives; deskewing returns the scene to float precision. Turn
  // rates from none to a 5 rad/s spin (where the angle leaves the small-angle series).
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> coord(-60.0, 60.0), time(-0.1, 0.18);
  const Eigen::Vector3d v(12.0, -0.4, 0.1);
  for (const Eigen::Vector3d& w :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.0, 0.0, 0.4), Eigen::Vector3d(0.02, -0.05, 1.1),
        Eigen::Vector3d(0.3, 0.2, -5.0)}) {
    std::vector<Eigen::Vector3d> scene;
    PointList points;
    std::vector<float> times;
    for (int i = 0; i < 2000; ++i) {
      scene.emplace_back(coord(rng), coord(rng), 0.05 * coord(rng));
      times.push_back(static_cast<float>(time(rng)));
      points.push_back(seenAt(scene.back(), times.back(), v, w));
    }
    ASSERT_TRUE(deskew(points, times, v, w));
    double worst = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
      worst = std::max(worst, (points[i].cast<double>() - scene[i]).norm());
    }
    // Two float roundings of coordinates up to 85 m (7.6e-6 m each), and the float times.
    EXPECT_LT(worst, 3e-5) << "w = " << w.transpose();
  }
}

TEST(Deskew, LeavesWhatItCannotMoveAndRefusesMismatchedTimes) {
  const Eigen::Vector3d v(5.0, 0.0, 0.0), w(0.0, 0.0, 0.5);
  PointList points = {{10.f, 0.f, 0.f}, {0.f, 10.f, 1.f}};
  const PointList before = points;
  EXPECT_TRUE(deskew(points, {}, v, w));  // no times: nothing to do
  EXPECT_EQ(points, before);
  EXPECT_FALSE(deskew(points, {0.05f}, v, w));  // one time for two points: refused, unchanged
  EXPECT_EQ(points, before);
  // A non-finite time leaves its point where it is; the other one moves by v t and turns.
  ASSERT_TRUE(deskew(points, {std::numeric_limits<float>::quiet_NaN(), 0.1f}, v, w));
  EXPECT_EQ(points[0], before[0]);
  EXPECT_NEAR(points[1].x(), 0.5 - 10.0 * std::sin(0.05), 1e-5);
  EXPECT_NEAR(points[1].y(), 10.0 * std::cos(0.05), 1e-5);
  EXPECT_FLOAT_EQ(points[1].z(), 1.f);
}

}  // namespace
}  // namespace gmm_localization
