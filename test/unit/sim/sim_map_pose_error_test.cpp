// MapPoseError on synthetic paths: exact poses for "none", residual in the configured band,
// smooth along the path, pinned back at a revisit, reproducible for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gmm_localization/sim/map_pose_error.h"

using gmm_localization::sim::MapPoseError;
using gmm_localization::sim::MapPoseErrorConfig;
using gmm_localization::sim::MapPoseErrorMode;
using gmm_localization::sim::parseMapPoseErrorMode;
using Poses = std::vector<Eigen::Isometry3d>;

namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d pose(double x, double y, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(x, y, 0.5);
  return p;
}

/// `laps` laps (fractional allowed) of a side x side square, one pose per metre.
Poses square(double side, double laps) {
  Poses out;
  const int n = static_cast<int>(4 * side * laps);
  for (int k = 0; k < n; ++k) {
    const double u = std::fmod(k, 4 * side);
    const int edge = static_cast<int>(u / side);
    const double t = u - edge * side;
    const double xs[] = {t, side, side - t, 0.0}, ys[] = {0.0, t, side, side - t};
    out.push_back(pose(xs[edge], ys[edge], edge * M_PI / 2));
  }
  return out;
}

Poses straight(int metres) {
  Poses out;
  for (int k = 0; k < metres; ++k) out.push_back(pose(k, 0.0, 0.0));
  return out;
}

double posErr(const Eigen::Isometry3d& m, const Eigen::Isometry3d& t) {
  return (m.translation() - t.translation()).norm();
}
Eigen::Matrix3d rotErr(const Eigen::Isometry3d& m, const Eigen::Isometry3d& t) {
  return m.linear() * t.linear().transpose();
}
double angle(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle(); }

MapPoseErrorConfig realistic() {
  MapPoseErrorConfig c;
  c.mode = MapPoseErrorMode::kRealistic;
  return c;
}

struct Rms {
  double m = 0.0, deg = 0.0;
};
Rms rms(const Poses& map, const Poses& truth) {
  Rms r;
  for (size_t i = 0; i < map.size(); ++i) {
    r.m += std::pow(posErr(map[i], truth[i]), 2);
    r.deg += std::pow(angle(rotErr(map[i], truth[i])) / kDeg, 2);
  }
  r.m = std::sqrt(r.m / map.size());
  r.deg = std::sqrt(r.deg / map.size());
  return r;
}

}  // namespace

TEST(MapPoseError, NoneGivesExactPoses) {
  const Poses truth = square(50, 2.5);
  const Poses out = MapPoseError(MapPoseErrorConfig{}).apply(truth);
  ASSERT_EQ(out.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) EXPECT_TRUE(out[i].isApprox(truth[i], 0.0)) << i;
}

TEST(MapPoseError, ResidualMatchesTheConfiguredValue) {
  MapPoseErrorConfig c = realistic();
  c.drift_m_per_100m = c.drift_deg_per_100m = 0.0;
  const Poses truth = straight(3000);
  for (double res : {0.03, 0.10}) {
    c.residual_m = res;
    c.residual_deg = 3.0 * res;  // 0.09 and 0.3 deg
    const Rms r = rms(MapPoseError(c).apply(truth), truth);
    EXPECT_NEAR(r.m, res, 0.25 * res);
    EXPECT_NEAR(r.deg, 3.0 * res, 0.25 * 3.0 * res);
  }
}

TEST(MapPoseError, DefaultsOnALoopedRouteAreInTheBand) {
  // Three laps of a 200 m block loop: the first lap carries the drift bridge, later ones close.
  const Poses truth = square(50, 3.0);
  for (uint64_t seed : {1, 2, 3}) {
    MapPoseErrorConfig c = realistic();
    c.seed = seed;
    const Rms r = rms(MapPoseError(c).apply(truth), truth);
    EXPECT_GE(r.m, 0.03) << seed;
    EXPECT_LE(r.m, 0.10) << seed;
    EXPECT_GE(r.deg, 0.1) << seed;
    EXPECT_LE(r.deg, 0.3) << seed;
  }
}

TEST(MapPoseError, ErrorIsSmoothAlongThePath) {
  const Poses truth = square(50, 3.0);  // one pose per metre
  const Poses map = MapPoseError(realistic()).apply(truth);
  double max_dp = 0.0, max_da = 0.0;
  for (size_t i = 1; i < truth.size(); ++i) {
    const Eigen::Vector3d e0 = map[i - 1].translation() - truth[i - 1].translation();
    const Eigen::Vector3d e1 = map[i].translation() - truth[i].translation();
    max_dp = std::max(max_dp, (e1 - e0).norm());
    max_da = std::max(
        max_da, angle(rotErr(map[i - 1], truth[i - 1]).transpose() * rotErr(map[i], truth[i])));
  }
  EXPECT_LT(max_dp, 0.03);        // m per metre of path
  EXPECT_LT(max_da, 0.1 * kDeg);  // per metre of path
  EXPECT_GT(max_dp, 0.0);
}

TEST(MapPoseError, DriftIsPulledBackAtARevisit) {
  MapPoseErrorConfig c = realistic();
  c.residual_m = c.residual_deg = 0.0;
  c.drift_m_per_100m = 1.0;  // large, so the effect is plain
  const Poses truth = square(100, 1.5);
  const std::vector<size_t> closures = MapPoseError(c).closures(truth);
  ASSERT_FALSE(closures.empty());
  const size_t first = closures.front();
  EXPECT_GE(first, 380u);  // the start is revisited at the end of the first lap
  EXPECT_LE(first, 400u);
  const Poses map = MapPoseError(c).apply(truth);
  double max_first_lap = 0.0;
  for (size_t i = 0; i < first; ++i)
    max_first_lap = std::max(max_first_lap, posErr(map[i], truth[i]));
  EXPECT_GT(max_first_lap, 0.1);
  EXPECT_LT(posErr(map[first], truth[first]), 1e-9);
  // Without the closure (no loop can be that long) the drift stays.
  c.min_loop_m = 1e6;
  EXPECT_TRUE(MapPoseError(c).closures(truth).empty());
  const Poses open = MapPoseError(c).apply(truth);
  EXPECT_GT(posErr(open[first], truth[first]), 0.05);
}

TEST(MapPoseError, SameSeedSameErrors) {
  const Poses truth = square(50, 2.0);
  MapPoseErrorConfig c = realistic();
  const Poses a = MapPoseError(c).apply(truth), b = MapPoseError(c).apply(truth);
  c.seed = 7;
  const Poses d = MapPoseError(c).apply(truth);
  bool differs = false;
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_TRUE(a[i].isApprox(b[i], 0.0)) << i;
    differs |= !a[i].isApprox(d[i], 1e-12);
  }
  EXPECT_TRUE(differs);
}

TEST(MapPoseError, BadInputIsRejected) {
  EXPECT_FALSE(parseMapPoseErrorMode("bogus"));
  EXPECT_TRUE(parseMapPoseErrorMode("realistic"));
  MapPoseErrorConfig c = realistic();
  EXPECT_TRUE(c.validate());
  c.drift_m_per_100m = -0.1;
  EXPECT_FALSE(c.validate());
  c = realistic();
  c.residual_deg = std::nan("");
  EXPECT_FALSE(c.validate());
  c = realistic();
  c.loop_radius_m = 0.0;
  EXPECT_FALSE(c.validate());
}
