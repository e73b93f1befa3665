#include "gmm_localization/sim/hdl32e.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

TEST(Hdl32e, ElevationTableIsTheRealInterleavedOne) {
  const auto& el = Hdl32eModel::elevationsDeg();
  EXPECT_NEAR(el[0], -30.67, 1e-2);  // firing order starts low,
  EXPECT_NEAR(el[1], -9.33, 1e-2);   // then jumps to the upper block
  EXPECT_NEAR(el[2], -29.33, 1e-2);
  EXPECT_NEAR(el[31], 10.67, 1e-2);
  EXPECT_NEAR(*std::min_element(el.begin(), el.end()), -30.67, 1e-2);
  EXPECT_NEAR(*std::max_element(el.begin(), el.end()), 10.67, 1e-2);
  // Rings sort the lasers by elevation, 4/3 deg apart.
  std::array<double, 32> by_ring{};
  for (int l = 0; l < 32; ++l) by_ring[Hdl32eModel::ringOfLaser(l)] = el[l];
  for (int r = 1; r < 32; ++r)
    EXPECT_NEAR(by_ring[r] - by_ring[r - 1], 4.0 / 3.0, 2e-3) << "ring " << r;
}

TEST(Hdl32e, TimingAndAzimuthStep) {
  Hdl32eModel full{Hdl32eConfig()};
  EXPECT_EQ(full.firingsPerRevolution(), 2170);
  EXPECT_NEAR(full.azimuthStepDeg(), 0.166, 1e-3);
  Hdl32eConfig coarse;
  coarse.firing_decimation = 4;
  Hdl32eModel m(coarse);
  EXPECT_EQ(m.firingsPerRevolution(), 542);
  EXPECT_NEAR(m.azimuthStepDeg(), 4 * 0.16589, 1e-3);
  EXPECT_NEAR(m.pointTime(1, 0) - m.pointTime(0, 0), 4 * 46.08e-6, 1e-12);
  EXPECT_NEAR(m.pointTime(0, 31), 31 * 1.152e-6, 1e-12);
  // Clockwise spin: the azimuth decreases with firing index.
  EXPECT_LT(m.azimuth(10), m.azimuth(9));
}

TEST(Hdl32e, PointTimeIsMonotonicInAzimuthWithinARevolution) {
  auto sim = testing::makeSimulation(testing::shortSegment(PassType::kMapping, 0.5));
  ASSERT_NE(sim, nullptr);
  MemorySink mem;
  ASSERT_TRUE(sim->run(mem).ok());
  ASSERT_FALSE(mem.revolutions.empty());
  for (const SensorRevolution& rev : mem.revolutions) {
    ASSERT_GT(rev.points.size(), 1000u);
    double last_time = -1.0;
    for (const LidarPoint& p : rev.points) {
      EXPECT_GE(p.time_s, last_time);  // stored in firing order
      EXPECT_LT(p.time_s, 0.1);
      EXPECT_LT(p.ring, 32);
      // Azimuth swept clockwise from the start (+y, 90 deg) is 360 deg per 0.1 s of point time,
      // so with time non-decreasing the azimuth is monotonic too.
      const double az = std::atan2(p.y, p.x) * 180.0 / M_PI;
      double diff = (90.0 - az) - 3600.0 * p.time_s;
      diff = std::remainder(diff, 360.0);
      EXPECT_NEAR(diff, 0.0, 0.2) << "time " << p.time_s;
      last_time = p.time_s;
    }
  }
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
