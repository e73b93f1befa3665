// The snowy pass: the snow cover raises the ground by 5-15 cm (more in the gutters), flakes and
// snowbanks return label-2 points, and lane paint no longer shows in the intensities.
#include <algorithm>

#include <gtest/gtest.h>

#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

struct GroundStats {
  double median_rise = 0.0;  // z - bare ground height, road points near the car
  size_t snow_points = 0, road = 0, total = 0, paint = 0;
  double paint_intensity = 0.0, plain_intensity = 0.0;  // means over road points
};

GroundStats groundStats(PassType type) {
  SimulationConfig c = testing::shortSegment(type, 0.5);
  c.pass.moving_cars_per_km2 = c.pass.pedestrians_per_km2 = 0.0;
  c.kinematics.seed = 4;  // same drive in both passes
  auto sim = testing::makeSimulation(c);
  GroundStats g;
  if (!sim) return g;
  MemorySink mem;
  if (!sim->run(mem).ok()) return g;
  std::vector<double> rise;
  const Town& town = sim->town();
  for (const DeskewedScan& s : mem.deskewed) {
    for (const LidarPoint& p : s.points) {
      ++g.total;
      if (p.label == kLabelSnow) ++g.snow_points;
      const Eigen::Vector3d q = s.base_to_map * Eigen::Vector3d(p.x, p.y, p.z);
      const double r = Eigen::Vector2d(p.x, p.y).norm();
      if (p.label != kLabelStatic || r > 20.0 || !town.onRoad(q.x(), q.y())) continue;
      const double dz = q.z() - town.groundHeight(q.x(), q.y());
      if (std::abs(dz) > 0.5) continue;  // not ground (cars, banks)
      rise.push_back(dz);
      ++g.road;
      if (town.markingAt(q.x(), q.y())) {
        ++g.paint;
        g.paint_intensity += p.intensity;
      } else {
        g.plain_intensity += p.intensity;
      }
    }
  }
  g.paint_intensity /= std::max<size_t>(1, g.paint);
  g.plain_intensity /= std::max<size_t>(1, g.road - g.paint);
  if (!rise.empty()) {
    std::nth_element(rise.begin(), rise.begin() + rise.size() / 2, rise.end());
    g.median_rise = rise[rise.size() / 2];
  }
  return g;
}

TEST(SimSnow, SnowRaisesTheGroundAndAddsSnowReturns) {
  const GroundStats clear = groundStats(PassType::kMapping);
  const GroundStats snowy = groundStats(PassType::kSnowy);
  ASSERT_GT(clear.road, 2000u);
  ASSERT_GT(snowy.road, 2000u);
  EXPECT_NEAR(clear.median_rise, 0.0, 0.01);
  // Cover 5-15 cm plus half the crown filled in the gutters (<= 6 cm).
  EXPECT_GT(snowy.median_rise, 0.05);
  EXPECT_LT(snowy.median_rise, 0.21);
  EXPECT_EQ(clear.snow_points, 0u);
  EXPECT_GT(snowy.snow_points, snowy.total / 200);  // falling snow, banks
  // Lane paint: bright against asphalt in the clear pass, invisible under snow.
  ASSERT_GT(clear.paint, 20u);
  ASSERT_GT(snowy.paint, 20u);
  EXPECT_GT(clear.paint_intensity, 3.0 * clear.plain_intensity);
  EXPECT_NEAR(snowy.paint_intensity / snowy.plain_intensity, 1.0, 0.25);
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
