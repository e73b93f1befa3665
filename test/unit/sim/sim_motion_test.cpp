// Motion distortion: driving at speed v toward a wall, a sensor whose revolution starts and ends
// facing the wall sees it about v x 0.1 s closer at the end of the revolution than at its start.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "gmm_localization/sim/lidar_simulator.h"
#include "gmm_localization/sim/scan_merge.h"
#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

TEST(SimMotion, WallComesCloserByVelocityTimesTime) {
  auto town = Town::generate(testing::smallTown());
  ASSERT_TRUE(town);
  RouteConfig rc;
  rc.nodes = {{0, 1}, {1, 1}, {2, 1}, {3, 1}};  // straight east along one road
  auto route = Route::plan(*town, rc);
  ASSERT_TRUE(route) << route.error();
  KinematicsConfig kc;
  kc.stop_probability = 0.0;
  kc.lane_wander_m = 0.0;
  auto traj = Trajectory::create(*town, *route, kc);
  ASSERT_TRUE(traj);
  // A moment at cruise speed mid-route.
  double t0 = traj->timeAtDistance(0.5 * route->length());
  t0 = std::floor(t0 * 10.0) / 10.0;
  const double v = traj->speedAt(t0 + 0.05);
  ASSERT_GT(v, 8.0);
  const Eigen::Isometry3d pose0 = traj->pose(t0);
  const Eigen::Vector3d fwd = pose0.linear().col(0);
  // A 12 m x 12 m wall across the lane, 25 m ahead.
  const Eigen::Vector3d c = pose0.translation() + 25.0 * fwd;
  const Eigen::Vector3d side = pose0.linear().col(1) * 6.0, up(0, 0, 12.0);
  TriangleMesh wall;
  addQuad(wall, c - side - Eigen::Vector3d(0, 0, 1), c + side - Eigen::Vector3d(0, 0, 1),
          c + side + up, c - side + up, {Material::kWall, kLabelStatic});
  auto world = World::create(*town, PassConfig::defaults(PassType::kMapping), 2, &wall);
  ASSERT_TRUE(world);
  RigConfig rig = RigConfig::single(1.95, 0.0);
  Hdl32eConfig hc;
  hc.start_azimuth_deg = 0.0;  // the revolution starts and ends facing forward
  hc.range_noise_m = 0.0;
  LidarSimulator lidar(*world, *traj, rig, hc, 5, 2);
  const int64_t index = static_cast<int64_t>(std::llround(t0 / 0.1));
  const SensorRevolution rev = lidar.simulate(0, index);
  ASSERT_NEAR(rev.t_start, t0, 1e-9);

  // Forward points (|azimuth| < 5 deg) on the wall: early ones (first 5 ms) and late ones
  // (last 5 ms); their x (distance along the sensor's forward axis) shrinks by v * dt. Medians
  // keep the odd pole or sign in front of the wall out.
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::vector<double> ex, et, lx, lt;
  for (const LidarPoint& p : rev.points) {
    if (std::abs(std::atan2(p.y, p.x)) > 5.0 * M_PI / 180.0 || p.x < 20.0 || p.z < -1.0) continue;
    if (p.time_s < 0.005) {
      ex.push_back(p.x);
      et.push_back(p.time_s);
    }
    if (p.time_s > 0.095) {
      lx.push_back(p.x);
      lt.push_back(p.time_s);
    }
  }
  ASSERT_GT(ex.size(), 20u);
  ASSERT_GT(lx.size(), 20u);
  const double early_x = median(ex), early_t = median(et), late_x = median(lx), late_t = median(lt);
  const double expected = v * (late_t - early_t);
  EXPECT_GT(expected, 0.8);
  const double moved =
      (traj->pose(t0 + late_t).translation() - traj->pose(t0 + early_t).translation()).dot(fwd);
  std::printf("v %.3f, moved %.4f m, v dt %.4f m, wall shrink %.4f m\n", v, moved, expected,
              early_x - late_x);
  EXPECT_NEAR(early_x - late_x, expected, 0.03) << "v=" << v;  // sign: late points are closer
  // Deskewing with ground truth removes the distortion: the wall is one plane in map frame.
  const std::vector<LidarPoint> fixed =
      deskewToStamp({rev}, rig, lidar.model(), *traj, rev.t_start);
  std::vector<double> e, l;
  for (const LidarPoint& p : fixed) {
    if (std::abs(std::atan2(p.y, p.x)) > 5.0 * M_PI / 180.0 || p.x < 20.0 || p.z < 0.8) continue;
    if (p.time_s < 0.005) e.push_back(p.x);
    if (p.time_s > 0.095) l.push_back(p.x);
  }
  ASSERT_GT(e.size(), 20u);
  ASSERT_GT(l.size(), 20u);
  EXPECT_NEAR(median(e), median(l), 0.02);
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
