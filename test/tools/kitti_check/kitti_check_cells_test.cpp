// The cell classifier of kitti_check on a synthetic street corner with known classes: flat
// ground, a wall, a tree crown and mirrored returns below the road.
#include <gtest/gtest.h>

#include <random>

#include "kitti_check/kitti_check_cells.h"

using namespace gmm_localization;
using namespace gmm_localization::kitti_check;

namespace {

struct Scene {
  PointList points;
  std::vector<PointClass> truth;
  void add(const Eigen::Vector3f& p, PointClass c) {
    points.push_back(p);
    truth.push_back(c);
  }
};

Scene makeScene(uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 0.02f);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  Scene s;
  const float road = -1.7f;  // sensor frame height of the road, gently sloping in x
  auto ground = [&](float x) { return road + 0.01f * x; };
  for (float x = -10.f; x <= 10.f; x += 0.25f) {
    for (float y = -10.f; y <= 10.f; y += 0.25f) {
      s.add({x, y, ground(x) + noise(rng)}, PointClass::kGround);
    }
  }
  // A wall along y = 8, x in [-8, 8], 3 m tall.
  for (float x = -8.f; x <= 8.f; x += 0.25f) {
    for (float z = 0.5f; z <= 3.f; z += 0.25f) {
      s.add({x, 8.f + noise(rng), ground(x) + z}, PointClass::kWall);
    }
  }
  // A tree crown: uniform in a ball of radius 1.5 m centred 3.5 m above the road at (-5, -5).
  for (int i = 0; i < 1500; ++i) {
    Eigen::Vector3f d;
    do {
      d = Eigen::Vector3f(u(rng), u(rng), u(rng)) * 2.f - Eigen::Vector3f::Ones();
    } while (d.norm() > 1.f);
    s.add(Eigen::Vector3f(-5.f, -5.f, ground(-5.f) + 3.5f) + 1.5f * d, PointClass::kVegetation);
  }
  // Mirror ghosts: a vertical streak 2-5 m under the road at (4, -4).
  for (float z = 2.f; z <= 5.f; z += 0.25f) {
    s.add({4.f, -4.f, ground(4.f) - z}, PointClass::kBelowGround);
  }
  return s;
}

double recall(const Scene& s, const PointLabels& l, PointClass c) {
  int n = 0, ok = 0;
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (s.truth[i] != c) continue;
    ++n;
    ok += l.labels[i] == c;
  }
  return n > 0 ? static_cast<double>(ok) / n : 0.0;
}

}  // namespace

TEST(KittiCheckCells, ClassifiesGroundWallVegetationAndGhosts) {
  const Scene s = makeScene(7);
  const PointLabels l = classifyPoints(s.points, ClassifierOptions());
  ASSERT_EQ(l.labels.size(), s.points.size());
  EXPECT_GT(recall(s, l, PointClass::kGround), 0.99);
  EXPECT_GT(recall(s, l, PointClass::kWall), 0.85);  // the wall's ends and top edge are linear
  EXPECT_GT(recall(s, l, PointClass::kVegetation), 0.8);
  EXPECT_EQ(recall(s, l, PointClass::kBelowGround), 1.0);
  // The ghosts do not pull the ground level down: every ground point sits on its level.
  for (size_t i = 0; i < s.points.size(); ++i) {
    if (s.truth[i] == PointClass::kGround) {
      ASSERT_NEAR(l.ground_z[i], s.points[i].z(), 0.3) << "point " << i;
    }
  }
}

TEST(KittiCheckCells, CellsTakeTheirPointsClassAndMixture) {
  const Scene s = makeScene(3);
  const PointLabels l = classifyPoints(s.points, ClassifierOptions());
  GmmMap map(MapGeometry{});
  auto tile = std::make_shared<GmmTile>(TileId{-1, -1}, map.geometry().tile_size_cells);
  map.insert(tile);
  // Give every cell of tile (-1, -1) (x, y in [-64, 0) m) a one-component mixture.
  for (auto& g : tile->cells()) g.add({1.f, -1.7f, 0.05f});
  const std::vector<CellRecord> cells = classifyCells(map, s.points, l);
  ASSERT_FALSE(cells.empty());
  bool saw_tree = false, saw_ground = false;
  for (const CellRecord& c : cells) {
    EXPECT_LT(c.centre.x(), 0.0);  // cells of the absent tiles have no mixture: skipped
    EXPECT_LT(c.centre.y(), 0.0);
    EXPECT_EQ(c.mixture.size(), 1);
    if ((c.centre - Eigen::Vector2d(-5, -5)).norm() < 0.5) {
      saw_tree = true;
      EXPECT_EQ(c.cls, PointClass::kVegetation);
    }
    if ((c.centre - Eigen::Vector2d(-2, -8)).norm() < 0.3) {
      saw_ground = true;
      EXPECT_EQ(c.cls, PointClass::kGround);
    }
  }
  EXPECT_TRUE(saw_tree);
  EXPECT_TRUE(saw_ground);
  const std::vector<size_t> examples = exampleCells(cells);
  ASSERT_FALSE(examples.empty());
  for (size_t i : examples) EXPECT_LT(i, cells.size());
}
