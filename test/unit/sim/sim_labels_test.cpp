// Ground-truth labels: points on moving actors and changed parked cars carry label 1, and
// points labelled 1 lie on such objects; the mapping pass has no label 1 or 2.
#include <gtest/gtest.h>

#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

/// True if map point q lies within `margin` of an actor's box at time t.
bool onActor(const World& world, const Eigen::Vector3d& q, double t, double margin) {
  for (const Actor& a : world.pass().actors) {
    Eigen::Isometry3d pose;
    a.poseAt(world.town(), t, &pose);
    const Eigen::Vector3d l = pose.inverse() * q;
    const double hl = a.kind == Actor::Kind::kCar ? 0.5 * a.shape.length_m : 0.3;
    const double hw = a.kind == Actor::Kind::kCar ? 0.5 * a.shape.width_m : 0.35;
    const double h = a.kind == Actor::Kind::kCar ? a.shape.height_m : 1.75;
    if (std::abs(l.x()) < hl + margin && std::abs(l.y()) < hw + margin && l.z() > -margin &&
        l.z() < h + margin)
      return true;
  }
  return false;
}

TEST(SimLabels, DynamicObjectsAreLabelledAndOnlyThey) {
  SimulationConfig c = testing::shortSegment(PassType::kDowntown, 0.5);
  c.pass.moving_cars_per_km2 = 300.0;
  c.pass.pedestrians_per_km2 = 3000.0;
  c.pass.parked_keep_probability = 1.0;  // only actors are dynamic here
  auto sim = testing::makeSimulation(c);
  ASSERT_TRUE(sim);
  MemorySink mem;
  ASSERT_TRUE(sim->run(mem).ok());
  size_t dynamic = 0, static_on_actor = 0, checked = 0;
  for (const SensorRevolution& rev : mem.revolutions) {
    const Eigen::Isometry3d& t_bs = c.rig.sensors[rev.sensor].base_to_sensor;
    for (const LidarPoint& p : rev.points) {
      const double t = rev.t_start + p.time_s;
      const Eigen::Vector3d q = sim->trajectory().pose(t) * t_bs * Eigen::Vector3d(p.x, p.y, p.z);
      if (p.label == kLabelDynamic) {
        ++dynamic;
        EXPECT_TRUE(onActor(sim->world(), q, t, 0.15))
            << "label-1 point off every actor at t=" << t;
      } else if (p.label == kLabelStatic && (++checked % 7 == 0)) {
        static_on_actor += onActor(sim->world(), q, t, -0.2);  // deep inside an actor
      }
      EXPECT_NE(p.label, kLabelSnow);
    }
  }
  EXPECT_GT(dynamic, 200u);
  EXPECT_EQ(static_on_actor, 0u);
}

TEST(SimLabels, ChangedParkedCarsAreDynamicAndMappingIsAllStatic) {
  SimulationConfig c = testing::shortSegment(PassType::kDowntown, 0.3);
  c.pass.moving_cars_per_km2 = c.pass.pedestrians_per_km2 = 0.0;
  c.pass.parked_keep_probability = 0.0;  // every slot redrawn
  c.pass.parked_occupancy = 0.9;
  auto sim = testing::makeSimulation(c);
  ASSERT_TRUE(sim);
  size_t changed = 0;
  for (const ParkedCar& car : sim->world().pass().parked) changed += car.label == kLabelDynamic;
  EXPECT_EQ(changed, sim->world().pass().parked.size());
  MemorySink mem;
  ASSERT_TRUE(sim->run(mem).ok());
  size_t dynamic = 0;
  for (const MergedScan& s : mem.merged)
    for (const LidarPoint& p : s.points) dynamic += p.label == kLabelDynamic;
  EXPECT_GT(dynamic, 100u);

  SimulationConfig m = testing::shortSegment(PassType::kMapping, 0.3);
  auto map_sim = testing::makeSimulation(m);
  ASSERT_TRUE(map_sim);
  MemorySink map_mem;
  ASSERT_TRUE(map_sim->run(map_mem).ok());
  ASSERT_FALSE(map_mem.merged.empty());
  for (const MergedScan& s : map_mem.merged)
    for (const LidarPoint& p : s.points) ASSERT_EQ(p.label, kLabelStatic);
}

TEST(SimLabels, UnchangedParkedCarsMatchTheMappingPass) {
  auto town = Town::generate(testing::smallTown());
  ASSERT_TRUE(town);
  PassConfig keep = PassConfig::defaults(PassType::kDowntown, 9);
  keep.parked_keep_probability = 1.0;
  const PassContents mapping = preparePass(*town, PassConfig::defaults(PassType::kMapping));
  const PassContents local = preparePass(*town, keep);
  ASSERT_EQ(mapping.parked.size(), local.parked.size());
  for (size_t k = 0; k < mapping.parked.size(); ++k) {
    EXPECT_EQ(mapping.parked[k].center, local.parked[k].center);
    EXPECT_EQ(local.parked[k].label, kLabelStatic);
  }
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
