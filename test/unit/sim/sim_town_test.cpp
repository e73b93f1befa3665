#include <cmath>

#include <gtest/gtest.h>

#include "gmm_localization/sim/route.h"
#include "gmm_localization/sim/town.h"
#include "gmm_localization/sim/town_mesh.h"
#include "sim_test_fixtures.h"

namespace gmm_localization {
namespace sim {
namespace {

TEST(Town, SameSeedSameTownOtherSeedOtherTown) {
  auto a = Town::generate(testing::smallTown(5));
  auto b = Town::generate(testing::smallTown(5));
  auto c = Town::generate(testing::smallTown(6));
  ASSERT_TRUE(a && b && c);
  EXPECT_EQ(a->objects().vertices, b->objects().vertices);
  EXPECT_EQ(a->roadX(), b->roadX());
  EXPECT_NE(a->objects().vertices, c->objects().vertices);
  EXPECT_GT(a->objects().numTriangles(), 10000u);  // buildings, trees, poles
  EXPECT_GT(a->parkingSlots().size(), 50u);
}

TEST(Town, CrownedRoadsCurbsAndPaint) {
  auto t = Town::generate(testing::smallTown());
  ASSERT_TRUE(t);
  const TownConfig& c = t->config();
  const double x = t->roadX()[1];
  const double y = 0.5 * (t->roadY()[0] + t->roadY()[1]);  // mid-block on a north-south road
  const double half = 0.5 * c.road_width_m;
  EXPECT_TRUE(t->onRoad(x + 3.0, y));
  EXPECT_FALSE(t->onRoad(x + half + 1.0, y));
  // Crown: centre above gutter by crown_height; curb: sidewalk above gutter by curb_height.
  EXPECT_NEAR(t->groundHeight(x + 0.01, y) - t->terrainHeight(x + 0.01, y), c.crown_height_m, 1e-3);
  EXPECT_NEAR(t->groundHeight(x + half - 0.01, y) - t->terrainHeight(x + half - 0.01, y), 0.0,
              2e-3);
  EXPECT_NEAR(t->groundHeight(x + half + 0.01, y) - t->terrainHeight(x + half + 0.01, y),
              c.curb_height_m, 1e-9);
  EXPECT_TRUE(t->markingAt(x + 0.12, y));  // double centre line
  EXPECT_FALSE(t->markingAt(x + 1.0, y));
  // Gentle slope: at most a few percent between two points 100 m apart.
  EXPECT_LT(std::abs(t->terrainHeight(0, 0) - t->terrainHeight(100, 0)) / 100.0, 0.05);
}

TEST(Town, GroundMeshFollowsTheSurfaceAndCoverRaisesIt) {
  auto t = Town::generate(testing::smallTown());
  ASSERT_TRUE(t);
  const TriangleMesh bare = buildGroundMesh(*t);
  GroundCover cover;
  cover.depth_m = [](double, double) { return 0.1; };
  const TriangleMesh snowy = buildGroundMesh(*t, cover);
  ASSERT_EQ(bare.numVertices(), snowy.numVertices());
  for (size_t v = 0; v < bare.numVertices(); v += 97) {
    EXPECT_NEAR(snowy.vertices[3 * v + 2] - bare.vertices[3 * v + 2], 0.1, 1e-4);
  }
  for (Material m : snowy.materials) EXPECT_EQ(m, Material::kSnow);
}

TEST(Route, DrivesRoadsInBothDirectionsWithoutUTurns) {
  auto t = Town::generate(testing::smallTown());
  ASSERT_TRUE(t);
  RouteConfig rc;
  rc.length_m = 1500.0;
  auto r = Route::plan(*t, rc);
  ASSERT_TRUE(r) << r.error();
  EXPECT_NEAR(r->length(), 1500.0, 200.0);
  EXPECT_GT(r->bothDirectionsShare(), 0.3);
  // Continuous path: consecutive samples 1 m apart are 1 m apart, on the right-hand lane.
  for (double s = 0.0; s + 1.0 < r->length(); s += 1.0) {
    const PathPoint a = r->at(s), b = r->at(s + 1.0);
    EXPECT_NEAR((b.position - a.position).norm(), 1.0, 0.02) << "s=" << s;
    EXPECT_LE(std::abs(a.curvature), 1.0 / rc.right_turn_radius_m + 1e-9);
    EXPECT_TRUE(t->onRoad(a.position.x(), a.position.y()));
  }
  RouteConfig bad;
  bad.nodes = {{0, 0}, {2, 0}};
  EXPECT_FALSE(Route::plan(*t, bad).ok());
}

TEST(Trajectory, RespectsKinematicLimits) {
  auto t = Town::generate(testing::smallTown());
  ASSERT_TRUE(t);
  RouteConfig rc;
  rc.length_m = 1200.0;
  auto r = Route::plan(*t, rc);
  ASSERT_TRUE(r);
  KinematicsConfig kc;
  auto tr = Trajectory::create(*t, *r, kc);
  ASSERT_TRUE(tr) << tr.error();
  EXPECT_NEAR(tr->distanceAt(tr->duration()), r->length(), 1e-6);
  double vmax = 0.0;
  int stopped = 0;
  for (double time = 0.0; time < tr->duration(); time += 0.01) {
    const VehicleState s = tr->state(time);
    vmax = std::max(vmax, s.speed_mps);
    stopped += s.speed_mps < 1e-6;
    const Eigen::Vector3d fwd = s.pose.linear().col(0);
    const double a_long = s.acceleration_world.dot(fwd);
    const double a_lat = (s.acceleration_world - a_long * fwd).head<2>().norm();
    if (time > 0.05 && time < tr->duration() - 0.05) {  // differences clamp at the ends
      EXPECT_LT(a_long, kc.max_accel_mps2 + 0.15) << "t=" << time;
      EXPECT_GT(a_long, -kc.max_decel_mps2 - 0.15) << "t=" << time;
      EXPECT_LT(a_lat, kc.max_lateral_accel_mps2 * 1.1 + 0.3) << "t=" << time;
    }
    // Small roll and pitch from terrain and crown.
    const Eigen::Vector3d up = s.pose.linear().col(2);
    EXPECT_GT(up.z(), std::cos(5.0 * M_PI / 180.0));
  }
  EXPECT_LE(vmax, kc.max_speed_mps + 1e-9);
  EXPECT_GT(vmax, 8.0);
  EXPECT_GT(stopped, 10);  // starts and ends at rest
}

}  // namespace
}  // namespace sim
}  // namespace gmm_localization
