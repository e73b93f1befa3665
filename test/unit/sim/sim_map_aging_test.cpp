// Map aging: an aged localization pass holds the construction sites, containers, grown crowns
// (all labelled dynamic) and repaved stretches, parked cars under them are gone, the mapping
// pass is untouched, the plan is deterministic per seed; ray casting sees fresh asphalt and
// no (or shifted) paint on a repaved stretch.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

MapAgingConfig realistic(uint64_t seed) {
  MapAgingConfig c;
  c.mode = MapAgingMode::kRealistic;
  c.seed = seed;
  return c;
}

PassConfig agedPass(uint64_t seed) {
  PassConfig p = PassConfig::defaults(PassType::kDowntown, 5);
  p.moving_cars_per_km2 = p.pedestrians_per_km2 = 0.0;
  p.aging = realistic(seed);
  return p;
}

Footprint carFootprint(const ParkedCar& c) {
  Footprint f;
  f.center = c.center;
  f.yaw_rad = c.yaw_rad;
  f.half_length_m = 0.5 * c.shape.length_m;
  f.half_width_m = 0.5 * c.shape.width_m;
  return f;
}

bool samePlan(const MapAging& a, const MapAging& b) {
  if (a.sites.size() != b.sites.size() || a.containers.size() != b.containers.size() ||
      a.grown_trees.size() != b.grown_trees.size() || a.repaved.size() != b.repaved.size())
    return false;
  for (size_t k = 0; k < a.sites.size(); ++k)
    if (a.sites[k].fence.center != b.sites[k].fence.center) return false;
  for (size_t k = 0; k < a.containers.size(); ++k)
    if (a.containers[k].center != b.containers[k].center) return false;
  for (size_t k = 0; k < a.grown_trees.size(); ++k)
    if (a.grown_trees[k].tree != b.grown_trees[k].tree) return false;
  for (size_t k = 0; k < a.repaved.size(); ++k)
    if (!a.repaved[k].area.isApprox(b.repaved[k].area)) return false;
  return true;
}

TEST(SimMapAging, TownRecordsEveryTree) {
  auto town = Town::generate(testing::smallTown());
  ASSERT_TRUE(town);
  // Every tree has one six-sided bark prism (18 triangles) in the objects mesh.
  size_t bark = 0;
  for (Material m : town->objects().materials) bark += m == Material::kBark;
  ASSERT_GT(town->trees().size(), 50u);
  EXPECT_EQ(bark, 18 * town->trees().size());
  for (const TreeCrown& t : town->trees()) {
    EXPECT_GE(t.radius_h_m, 1.8);
    EXPECT_LE(t.radius_h_m, 3.5);
    EXPECT_GT(t.center.z(), town->groundHeight(t.center.x(), t.center.y()) + 2.0);
  }
}

TEST(SimMapAging, PlanHasTheConfiguredDensitiesWithoutOverlaps) {
  auto town = Town::generate(testing::smallTown());
  ASSERT_TRUE(town);
  const MapAgingConfig c = realistic(3);
  const MapAging a = planMapAging(*town, c);
  // The small town has 2 x 5 road lines of 400 m: 4 km of road.
  EXPECT_EQ(a.sites.size(), 4u);       // 1 per km
  EXPECT_EQ(a.containers.size(), 6u);  // 1.5 per km
  EXPECT_EQ(a.repaved.size(), 2u);     // 0.5 per km
  const double share = static_cast<double>(a.grown_trees.size()) / town->trees().size();
  EXPECT_NEAR(share, c.tree_share, 0.08);
  for (const GrownTree& g : a.grown_trees) {
    EXPECT_GE(g.growth_m, c.tree_growth_min_m);
    EXPECT_LE(g.growth_m, c.tree_growth_max_m);
  }
  const auto& slots = town->parkingSlots();
  std::vector<Footprint> objects;
  for (const ConstructionSite& s : a.sites) {
    // Two or three consecutive slots of one kerb inside the fence.
    int covered = 0;
    for (const ParkingSlot& slot : slots) {
      Footprint point;
      point.center = slot.center;
      covered += s.fence.overlaps(point);
    }
    EXPECT_TRUE(covered == 2 || covered == 3) << covered;
    if (s.has_container) {
      EXPECT_TRUE(s.fence.overlaps(s.container));
      EXPECT_LT((s.container.center - s.fence.center).norm(), 1.0);
    }
    objects.push_back(s.fence);
  }
  for (const Footprint& f : a.containers) {
    EXPECT_DOUBLE_EQ(2.0 * f.half_length_m, kContainerLengthM);
    EXPECT_DOUBLE_EQ(2.0 * f.half_width_m, kContainerWidthM);
    double nearest = 1e9;
    for (const ParkingSlot& slot : slots)
      nearest = std::min(nearest, (slot.center - f.center).norm());
    EXPECT_LT(nearest, 0.4);  // in a slot (0.07 m toward the kerb, +-0.2 m along it)
    objects.push_back(f);
  }
  for (size_t i = 0; i < objects.size(); ++i)
    for (size_t j = i + 1; j < objects.size(); ++j)
      EXPECT_FALSE(objects[i].overlaps(objects[j])) << i << " " << j;
  for (const RepavedStretch& r : a.repaved) {
    const double along = r.lateral.x() > 0.5 ? r.area.sizes().y() : r.area.sizes().x();
    const double across = r.lateral.x() > 0.5 ? r.area.sizes().x() : r.area.sizes().y();
    EXPECT_GE(along, c.repaved_min_m - 1e-9);
    EXPECT_LE(along, c.repaved_max_m + 1e-9);
    EXPECT_NEAR(across, town->config().road_width_m, 1e-9);
    EXPECT_TRUE(town->onRoad(r.area.center().x(), r.area.center().y()));
    if (r.repainted) {
      EXPECT_GE(std::abs(r.paint_shift_m), c.paint_shift_min_m);
      EXPECT_LE(std::abs(r.paint_shift_m), c.paint_shift_max_m);
    }
  }
}

TEST(SimMapAging, AgedPassHoldsTheObjectsAndMappingIsUnchanged) {
  auto town = Town::generate(testing::smallTown());
  ASSERT_TRUE(town);
  PassConfig fresh = agedPass(4);
  fresh.aging.mode = MapAgingMode::kNone;
  auto plain = World::create(*town, fresh, 2);
  auto aged = World::create(*town, agedPass(4), 2);
  auto again = World::create(*town, agedPass(4), 2);
  auto other = World::create(*town, agedPass(5), 2);
  ASSERT_TRUE(plain && aged && again && other);
  const MapAging& a = (*aged)->aging();
  EXPECT_TRUE((*plain)->aging().empty());
  ASSERT_FALSE(a.sites.empty());
  ASSERT_FALSE(a.containers.empty());
  ASSERT_FALSE(a.grown_trees.empty());
  EXPECT_TRUE(samePlan(a, (*again)->aging()));
  EXPECT_FALSE(samePlan(a, (*other)->aging()));
  EXPECT_EQ((*aged)->numStaticTriangles(), (*again)->numStaticTriangles());

  // Parked cars of the pass under a site or container are gone, and only those.
  const auto& before = (*plain)->pass().parked;
  const auto& after = (*aged)->pass().parked;
  size_t blocked = 0;
  TriangleMesh removed;
  for (const ParkedCar& car : before) {
    if (!a.blocks(carFootprint(car))) continue;
    ++blocked;
    addCar(removed, Eigen::Vector3d::Zero(), car.yaw_rad, car.shape, car.label);
  }
  EXPECT_GT(blocked, 0u);

  // The scene gains exactly the aging mesh (and loses the removed cars); every added triangle
  // is labelled dynamic.
  TriangleMesh added;
  addMapAgingMesh(
      *town, a, [&](double x, double y) { return town->groundHeight(x, y); }, &added);
  ASSERT_GT(added.numTriangles(), 32 * a.grown_trees.size());
  for (uint8_t label : added.labels) EXPECT_EQ(label, kLabelDynamic);
  EXPECT_EQ((*aged)->numStaticTriangles(),
            (*plain)->numStaticTriangles() + added.numTriangles() - removed.numTriangles());
  EXPECT_EQ(a.removed_parked_cars, blocked);
  EXPECT_EQ(after.size(), before.size() - blocked);
  for (const ParkedCar& car : after) {
    for (const Footprint& f : a.containers) EXPECT_FALSE(f.overlaps(carFootprint(car)));
    for (const ConstructionSite& s : a.sites) EXPECT_FALSE(s.fence.overlaps(carFootprint(car)));
  }

  // The mapping pass is never aged, whatever its configuration says.
  PassConfig mapping = PassConfig::defaults(PassType::kMapping);
  auto map_plain = World::create(*town, mapping, 2);
  mapping.aging = realistic(4);
  auto map_aged = World::create(*town, mapping, 2);
  ASSERT_TRUE(map_plain && map_aged);
  EXPECT_TRUE((*map_aged)->aging().empty());
  EXPECT_EQ((*map_aged)->numStaticTriangles(), (*map_plain)->numStaticTriangles());
  EXPECT_EQ((*map_aged)->pass().parked.size(), (*map_plain)->pass().parked.size());
}

TEST(SimMapAging, RoadSurfaceOfARepavedStretch) {
  auto town = Town::generate(testing::smallTown());
  ASSERT_TRUE(town);
  // A stretch over the middle of the first north-south segment; the double centre line lies
  // 0.06-0.18 m from the centreline, so 0.12 m east of it is paint in the old pattern.
  const double x = town->roadX()[1], half = 0.5 * town->config().road_width_m;
  const double y = 0.5 * (town->roadY()[0] + town->roadY()[1]);
  ASSERT_TRUE(town->markingAt(x + 0.12, y));
  ASSERT_FALSE(town->markingAt(x + 0.62, y));
  MapAging a;
  RepavedStretch r;
  r.area =
      Eigen::AlignedBox2d(Eigen::Vector2d(x - half, y - 20.0), Eigen::Vector2d(x + half, y + 20.0));
  r.lateral = Eigen::Vector2d(1.0, 0.0);
  a.repaved.push_back(r);
  EXPECT_EQ(roadSurfaceAt(*town, a, x + 0.12, y), Material::kAsphaltNew);          // no paint yet
  EXPECT_EQ(roadSurfaceAt(*town, a, x + 0.12, y + 30.0), Material::kLaneMarking);  // outside
  a.repaved[0].repainted = true;
  a.repaved[0].paint_shift_m = 0.5;
  EXPECT_EQ(roadSurfaceAt(*town, a, x + 0.12, y), Material::kAsphaltNew);   // old line gone
  EXPECT_EQ(roadSurfaceAt(*town, a, x + 0.62, y), Material::kLaneMarking);  // moved 0.5 m
  EXPECT_EQ(roadSurfaceAt(*town, MapAging{}, x + 0.12, y), Material::kLaneMarking);
  EXPECT_LT(materialResponse(Material::kAsphaltNew).reflectivity,
            materialResponse(Material::kAsphalt).reflectivity);
}

/// Mean intensities of road points near the car, split by repaved or not and by paint.
struct RoadIntensity {
  double sum[2][2] = {{0, 0}, {0, 0}};  // [repaved][old paint]
  size_t n[2][2] = {{0, 0}, {0, 0}};
  double sum_new_paint = 0.0;  // repaved and on the repainted lines
  size_t n_new_paint = 0;
  double mean(int repaved, int paint) const {
    return sum[repaved][paint] / std::max<size_t>(1, n[repaved][paint]);
  }
};

RoadIntensity roadIntensity(double repaint_probability) {
  SimulationConfig c = testing::shortSegment(PassType::kDowntown, 1.0);
  c.pass.moving_cars_per_km2 = c.pass.pedestrians_per_km2 = 0.0;
  c.pass.aging = realistic(2);
  c.pass.aging.sites_per_km = c.pass.aging.containers_per_km = c.pass.aging.tree_share = 0.0;
  c.pass.aging.repaved_per_km = 5.0;  // about half of the road segments, whole segments
  c.pass.aging.repaved_min_m = c.pass.aging.repaved_max_m = 1000.0;
  c.pass.aging.repaint_probability = repaint_probability;
  RoadIntensity out;
  auto sim = testing::makeSimulation(c);
  if (!sim) return out;
  MemorySink mem;
  if (!sim->run(mem).ok()) return out;
  const Town& town = sim->town();
  const MapAging& aging = sim->world().aging();
  for (const DeskewedScan& s : mem.deskewed) {
    for (const LidarPoint& p : s.points) {
      const Eigen::Vector3d q = s.base_to_map * Eigen::Vector3d(p.x, p.y, p.z);
      if (p.label != kLabelStatic || Eigen::Vector2d(p.x, p.y).norm() > 20.0 ||
          !town.onRoad(q.x(), q.y()) || std::abs(q.z() - town.groundHeight(q.x(), q.y())) > 0.1)
        continue;
      const RepavedStretch* r = aging.repavedAt(q.x(), q.y());
      const bool old_paint = town.markingAt(q.x(), q.y());
      // Repainted lines at the point, and within 0.1 m across the road (range noise moves
      // points by about 2 cm: points at a line's edge are left out).
      bool new_paint = false, new_paint_near = false;
      for (double d : {0.0, -0.1, 0.1}) {
        if (r == nullptr || !r->repainted) break;
        const double s = r->paint_shift_m + d;
        const bool at = town.markingAt(q.x() - s * r->lateral.x(), q.y() - s * r->lateral.y());
        (d == 0.0 ? new_paint : new_paint_near) |= at;
      }
      if (new_paint) {
        out.sum_new_paint += p.intensity;
        ++out.n_new_paint;
      }
      if (new_paint || new_paint_near) continue;
      out.sum[r != nullptr][old_paint] += p.intensity;
      ++out.n[r != nullptr][old_paint];
    }
  }
  return out;
}

TEST(SimMapAging, RayCastingSeesFreshAsphaltAndNoOldPaint) {
  const RoadIntensity missing = roadIntensity(0.0);  // stretches without paint
  for (int r = 0; r < 2; ++r)
    for (int p = 0; p < 2; ++p) ASSERT_GT(missing.n[r][p], 50u) << r << p;
  // Outside: paint bright against old asphalt. Inside: the old lines are plain fresh asphalt,
  // darker than the old surface (reflectivity 0.035 against 0.07).
  EXPECT_GT(missing.mean(0, 1), 3.0 * missing.mean(0, 0));
  EXPECT_LT(missing.mean(1, 1), 0.8 * missing.mean(0, 0));
  EXPECT_LT(missing.mean(1, 0), 0.8 * missing.mean(0, 0));
  EXPECT_EQ(missing.n_new_paint, 0u);

  const RoadIntensity repainted = roadIntensity(1.0);  // every stretch repainted, shifted
  ASSERT_GT(repainted.n[1][1], 50u);
  ASSERT_GT(repainted.n_new_paint, 50u);
  EXPECT_LT(repainted.mean(1, 1), 0.8 * repainted.mean(0, 0));  // where the paint was
  EXPECT_GT(repainted.sum_new_paint / repainted.n_new_paint, 3.0 * repainted.mean(1, 0));
}

TEST(SimMapAging, ConfigurationIsValidated) {
  EXPECT_TRUE(realistic(1).validate().ok());
  MapAgingConfig c = realistic(1);
  c.tree_share = 1.5;
  EXPECT_NE(c.validate().error().find("tree_share"), std::string::npos);
  c = realistic(1);
  c.tree_growth_min_m = 0.8;  // above the maximum
  EXPECT_NE(c.validate().error().find("tree_growth"), std::string::npos);
  PassConfig p = PassConfig::defaults(PassType::kSnowy);
  p.aging.sites_per_km = -1.0;
  EXPECT_NE(p.validate().error().find("sites_per_km"), std::string::npos);
  EXPECT_FALSE(parseMapAgingMode("old").ok());
  EXPECT_NE(PassConfig::defaults(PassType::kDowntown, 1).aging.seed,
            PassConfig::defaults(PassType::kDowntown, 2).aging.seed);
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
