// Extrinsic calibration error: the drawn errors lie in the configured band, are deterministic
// per seed; the simulator casts rays from the true (perturbed) mounts while merging and
// deskewing keep the nominal rig, so ground points placed with the nominal mounts are tilted
// and shifted by the drawn error and those placed with the true mounts are not.
#include <cmath>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "gmm_localization/sim/scan_merge.h"
#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

ExtrinsicErrorConfig realistic(uint64_t seed) {
  ExtrinsicErrorConfig c;
  c.mode = ExtrinsicErrorMode::kRealistic;
  c.seed = seed;
  return c;
}

TEST(SimExtrinsicError, DrawsLieInTheBandAndSpreadOverDirections) {
  const RigConfig nominal = RigConfig::fourRoofCorners();
  double t_min = 1.0, t_max = 0.0, r_min = 1.0, r_max = 0.0;
  Eigen::Vector3d t_dir_sum = Eigen::Vector3d::Zero(), r_axis_sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (uint64_t seed = 1; seed <= 200; ++seed) {
    const RigConfig truth = perturbedRig(nominal, realistic(seed));
    ASSERT_EQ(truth.sensors.size(), nominal.sensors.size());
    for (size_t k = 0; k < nominal.sensors.size(); ++k) {
      EXPECT_EQ(truth.sensors[k].frame_id, nominal.sensors[k].frame_id);
      EXPECT_EQ(truth.sensors[k].phase_s, nominal.sensors[k].phase_s);
      const MountError e = mountError(nominal.sensors[k], truth.sensors[k]);
      const double t = e.translation_m.norm(), r = e.rotation_rad.norm() / kDeg;
      EXPECT_GE(t, 0.01 - 1e-9);
      EXPECT_LE(t, 0.02 + 1e-9);
      EXPECT_GE(r, 0.1 - 1e-6);
      EXPECT_LE(r, 0.2 + 1e-6);
      t_min = std::min(t_min, t);
      t_max = std::max(t_max, t);
      r_min = std::min(r_min, r);
      r_max = std::max(r_max, r);
      t_dir_sum += e.translation_m.normalized();
      r_axis_sum += e.rotation_rad.normalized();
      ++n;
    }
  }
  // 800 draws uniform in the band reach close to both ends; directions have no preference
  // (the mean of 800 unit vectors uniform on the sphere has norm ~0.035).
  EXPECT_LT(t_min, 0.0102);
  EXPECT_GT(t_max, 0.0198);
  EXPECT_LT(r_min, 0.102);
  EXPECT_GT(r_max, 0.198);
  EXPECT_LT(t_dir_sum.norm() / n, 0.12);
  EXPECT_LT(r_axis_sum.norm() / n, 0.12);
}

TEST(SimExtrinsicError, DeterministicPerSeedAndNoneIsTheNominalRig) {
  const RigConfig nominal = RigConfig::fourRoofCorners();
  const RigConfig a = perturbedRig(nominal, realistic(7));
  const RigConfig b = perturbedRig(nominal, realistic(7));
  const RigConfig c = perturbedRig(nominal, realistic(8));
  for (size_t k = 0; k < nominal.sensors.size(); ++k) {
    EXPECT_TRUE(a.sensors[k].base_to_sensor.matrix() == b.sensors[k].base_to_sensor.matrix());
    EXPECT_GT(
        (a.sensors[k].base_to_sensor.translation() - c.sensors[k].base_to_sensor.translation())
            .norm(),
        1e-4);
    EXPECT_FALSE(a.sensors[k].base_to_sensor.matrix().isApprox(
        nominal.sensors[k].base_to_sensor.matrix(), 1e-6));
  }
  const RigConfig none = perturbedRig(nominal, ExtrinsicErrorConfig{});
  for (size_t k = 0; k < nominal.sensors.size(); ++k)
    EXPECT_TRUE(none.sensors[k].base_to_sensor.matrix() ==
                nominal.sensors[k].base_to_sensor.matrix());
  // Default seeds: a mapping pass and a drive (even with the same pass seed) differ.
  EXPECT_NE(SimulationConfig::defaults(PassType::kMapping, 1).extrinsic_error.seed,
            SimulationConfig::defaults(PassType::kDowntown, 1).extrinsic_error.seed);
  EXPECT_NE(SimulationConfig::defaults(PassType::kDowntown, 1).extrinsic_error.seed,
            SimulationConfig::defaults(PassType::kDowntown, 2).extrinsic_error.seed);
}

TEST(SimExtrinsicError, BadRangesAreRejectedByName) {
  ExtrinsicErrorConfig c = realistic(1);
  EXPECT_TRUE(c.validate().ok());
  c.translation_min_m = 0.03;  // above the maximum
  EXPECT_NE(c.validate().error().find("translation"), std::string::npos);
  c = realistic(1);
  c.rotation_max_deg = 20.0;
  EXPECT_NE(c.validate().error().find("rotation"), std::string::npos);
  EXPECT_FALSE(parseExtrinsicErrorMode("large").ok());
  EXPECT_TRUE(parseExtrinsicErrorMode("realistic").ok());
}

/// Least-squares plane dz = a + b vx + c vy over ground points, refitted once without the
/// points more than 3 RMS (at least 6 cm) off the first fit (wheels, curb edges).
struct Plane {
  double a = 0.0, b = 0.0, c = 0.0;
  size_t points = 0;
};
Plane fitPlane(const std::vector<Eigen::Vector3d>& samples) {  // (vx, vy, dz)
  Plane p;
  double limit = 1e9;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    double sq = 0.0;
    size_t n = 0;
    for (const Eigen::Vector3d& s : samples) {
      const double r = s.z() - (p.a + p.b * s.x() + p.c * s.y());
      if (std::abs(r) > limit) continue;
      const Eigen::Vector3d row(1.0, s.x(), s.y());
      ata += row * row.transpose();
      atb += row * s.z();
      sq += r * r;
      ++n;
    }
    const Eigen::Vector3d x = ata.ldlt().solve(atb);
    limit = std::max(0.06, 3.0 * std::sqrt(sq / std::max<size_t>(1, n)));
    p = {x(0), x(1), x(2), n};
  }
  return p;
}

TEST(SimExtrinsicError, RaysLeaveTheTrueMountsOutputsUseTheNominalOnes) {
  SimulationConfig c = testing::shortSegment(PassType::kMapping, 0.6);
  c.lidar.firing_decimation = 4;
  // Errors larger than realistic ones, so that the tilt stands well above the 2 cm range noise.
  c.extrinsic_error = realistic(11);
  c.extrinsic_error.translation_min_m = 0.03;
  c.extrinsic_error.translation_max_m = 0.05;
  c.extrinsic_error.rotation_min_deg = 0.4;
  c.extrinsic_error.rotation_max_deg = 0.6;
  auto sim = testing::makeSimulation(c);
  ASSERT_TRUE(sim);
  const RigConfig& nominal = c.rig;
  const RigConfig truth = perturbedRig(nominal, c.extrinsic_error);
  for (size_t k = 0; k < truth.sensors.size(); ++k)  // what the simulator says it casts from
    EXPECT_TRUE(sim->lidar().rig().sensors[k].base_to_sensor.matrix() ==
                truth.sensors[k].base_to_sensor.matrix());
  MemorySink mem;
  ASSERT_TRUE(sim->run(mem).ok());
  const Town& town = sim->town();
  auto onRoadInside = [&](const Eigen::Vector3d& q) {  // on the road, 0.5 m from the curbs
    for (double dx : {-0.5, 0.5})
      for (double dy : {-0.5, 0.5})
        if (!town.onRoad(q.x() + dx, q.y() + dy)) return false;
    return true;
  };

  // Ground points 3-10 m from their sensor, placed in the map with the nominal and with the
  // true mounts; (vx, vy) = horizontal offset from the sensor in base_link.
  std::map<int, std::vector<Eigen::Vector3d>> with_nominal, with_truth;
  for (const SensorRevolution& rev : mem.revolutions) {
    const SensorMount& mn = nominal.sensors[rev.sensor];
    const SensorMount& mt = truth.sensors[rev.sensor];
    for (const LidarPoint& p : rev.points) {
      const Eigen::Vector3d ps(p.x, p.y, p.z);
      const double range = ps.norm();
      if (range < 3.0 || range > 10.0) continue;
      const Eigen::Isometry3d pose = sim->trajectory().pose(rev.t_start + p.time_s);
      const Eigen::Vector3d bn = mn.base_to_sensor * ps, bt = mt.base_to_sensor * ps;
      const Eigen::Vector3d qn = pose * bn, qt = pose * bt;
      if (!onRoadInside(qn)) continue;
      const double dzn = qn.z() - town.groundHeight(qn.x(), qn.y());
      const double dzt = qt.z() - town.groundHeight(qt.x(), qt.y());
      if (std::abs(dzn) > 0.25 || std::abs(dzt) > 0.25) continue;  // not ground
      const Eigen::Vector2d v = (bn - mn.base_to_sensor.translation()).head<2>();
      with_nominal[rev.sensor].push_back({v.x(), v.y(), dzn});
      with_truth[rev.sensor].push_back({v.x(), v.y(), dzt});
    }
  }
  ASSERT_EQ(with_nominal.size(), nominal.sensors.size());
  double largest_tilt = 0.0;
  for (const auto& [sensor, samples] : with_nominal) {
    ASSERT_GT(samples.size(), 500u) << "sensor " << sensor;
    const MountError e = mountError(nominal.sensors[sensor], truth.sensors[sensor]);
    // The true ground seen through the nominal mount: rotated by R_err^-1 about the sensor and
    // moved by -dt, so dz = -dt_z + w_y vx - w_x vy for the rotation vector w.
    const Plane n = fitPlane(samples);
    EXPECT_NEAR(n.a, -e.translation_m.z(), 0.006) << "sensor " << sensor;
    EXPECT_NEAR(n.b, e.rotation_rad.y(), 0.05 * kDeg) << "sensor " << sensor;
    EXPECT_NEAR(n.c, -e.rotation_rad.x(), 0.05 * kDeg) << "sensor " << sensor;
    // Through the true mount the ground is where the town has it.
    const Plane t = fitPlane(with_truth[sensor]);
    EXPECT_NEAR(t.a, 0.0, 0.004) << "sensor " << sensor;
    EXPECT_NEAR(t.b, 0.0, 0.03 * kDeg) << "sensor " << sensor;
    EXPECT_NEAR(t.c, 0.0, 0.03 * kDeg) << "sensor " << sensor;
    largest_tilt = std::max(largest_tilt, std::hypot(e.rotation_rad.x(), e.rotation_rad.y()));
  }
  EXPECT_GT(largest_tilt, 0.2 * kDeg);  // the check above has something to see

  // The products the consumer gets are built with the nominal rig, not the true one.
  ASSERT_FALSE(mem.merged.empty());
  ASSERT_FALSE(mem.deskewed.empty());
  std::vector<SensorRevolution> cycle;
  for (const SensorRevolution& r : mem.revolutions)
    if (r.index == mem.merged.front().index) cycle.push_back(r);
  ASSERT_EQ(cycle.size(), nominal.sensors.size());
  auto same = [](const std::vector<LidarPoint>& a, const std::vector<LidarPoint>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z) return false;
    return true;
  };
  EXPECT_TRUE(same(mem.merged.front().points, mergeRevolutions(cycle, nominal).points));
  EXPECT_FALSE(same(mem.merged.front().points, mergeRevolutions(cycle, truth).points));
  const DeskewedScan& d = mem.deskewed.front();
  ASSERT_EQ(d.index, mem.merged.front().index);
  EXPECT_TRUE(same(
      d.points, deskewToStamp(cycle, nominal, sim->lidar().model(), sim->trajectory(), d.stamp)));
  EXPECT_FALSE(same(d.points,
                    deskewToStamp(cycle, truth, sim->lidar().model(), sim->trajectory(), d.stamp)));
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
