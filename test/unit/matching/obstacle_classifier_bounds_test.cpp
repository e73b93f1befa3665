// Obstacle labelling does bounded work per scan whatever the points hold: points beyond the
// sensor range, at absurd distances or non-finite are labelled kUnknown and counted, and a
// far-away or non-finite pose classifies nothing, without allocating a grid over the input.

#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/matching/obstacle_classifier.h"
#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace {

/// Flat ground z = 0 (sigma 5 cm) over chunk (0, 0): cells [0, 128)^2 of 0.2 m, i.e. x, y in
/// [0, 25.6) m.
class ObstacleBoundsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    MapGeometry g;
    g.resolution_m = 0.2;
    g.tile_size_cells = 128;
    GmmMap gmm(g);
    auto tile = std::make_shared<GmmTile>(TileId{0, 0}, 128);
    for (GaussianMixture1D& c : tile->cells()) c.add({1.f, 0.f, 0.05f});
    gmm.insert(tile);
    RasterOptions o;
    o.chunk_shift = 7;
    map_ = std::make_unique<ChunkMap>(g, o);
    map_->insert(rasterizeChunk(gmm, {0, 0}, o).value());
    pose_.x = 12.0;
    pose_.y = 12.0;
  }
  std::unique_ptr<ChunkMap> map_;
  Pose6 pose_;
};

TEST_F(ObstacleBoundsTest, FarAndNonFinitePointsAreUnknownAndNearOnesClassified) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  PointList scan;
  for (int i = 0; i < 50; ++i) scan.emplace_back(u(rng), u(rng), 0.f);  // ground: map
  scan.emplace_back(1.f, 1.f, 1.5f);                                    // 1.5 m above: obstacle
  scan.emplace_back(2e5f, 0.f, 0.f);                                    // beyond the range
  scan.emplace_back(1e30f, -1e30f, 0.f);
  scan.emplace_back(0.f, 0.f, 1e30f);  // vertical range counts too (roll/pitch mix z into x)
  scan.emplace_back(std::numeric_limits<float>::infinity(), 0.f, 0.f);
  scan.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f);
  scan.emplace_back(std::numeric_limits<float>::max(), 0.f, 0.f);
  const ObstacleLabels l = classifyObstacles(*map_, scan, pose_, ObstacleOptions());
  ASSERT_EQ(l.label.size(), scan.size());
  for (int i = 0; i < 50; ++i) EXPECT_EQ(l.label[i], PointClass::kMap) << i;
  EXPECT_EQ(l.label[50], PointClass::kObstacle);
  for (size_t i = 51; i < scan.size(); ++i) {
    EXPECT_EQ(l.label[i], PointClass::kUnknown) << i;
    EXPECT_TRUE(std::isinf(l.mahalanobis[i])) << i;
  }
  EXPECT_EQ(l.obstacles, 1u);
  EXPECT_EQ(l.over_empty_cells, 0u);
  EXPECT_EQ(l.unclassified, scan.size() - 51);
}

TEST_F(ObstacleBoundsTest, RangeOptionBoundsWhatIsClassified) {
  PointList scan = {{5.f, 0.f, 0.f}, {50.f, 0.f, 0.f}, {250.f, 0.f, 0.f}};
  ObstacleOptions o;
  o.max_range_m = 40.0;
  ObstacleLabels l = classifyObstacles(*map_, scan, pose_, o);
  EXPECT_EQ(l.label[0], PointClass::kMap);
  EXPECT_EQ(l.label[1], PointClass::kUnknown);
  EXPECT_EQ(l.label[2], PointClass::kUnknown);
  EXPECT_EQ(l.unclassified, 2u);
  // Default range: 50 m and 250 m are off the loaded chunk, so obstacles over empty cells.
  l = classifyObstacles(*map_, scan, pose_, ObstacleOptions());
  EXPECT_EQ(l.label[1], PointClass::kObstacle);
  EXPECT_EQ(l.label[2], PointClass::kObstacle);
  EXPECT_EQ(l.over_empty_cells, 2u);
  // A non-finite or huge range option is clamped to kMaxObstacleRangeM.
  o.max_range_m = std::numeric_limits<double>::infinity();
  scan.emplace_back(2e5f, 0.f, 0.f);
  l = classifyObstacles(*map_, scan, pose_, o);
  EXPECT_EQ(l.label[3], PointClass::kUnknown);
  o.max_range_m = std::numeric_limits<double>::quiet_NaN();
  l = classifyObstacles(*map_, scan, pose_, o);
  EXPECT_EQ(l.label[0], PointClass::kMap);
  EXPECT_EQ(l.label[3], PointClass::kUnknown);
}

TEST_F(ObstacleBoundsTest, UnusablePoseClassifiesNothing) {
  const PointList scan = {{1.f, 0.f, 0.f}, {2.f, 0.f, 0.f}};
  for (double bad : {std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity(), 1e30, -2e7}) {
    Pose6 p = pose_;
    p.x = bad;
    const ObstacleLabels l = classifyObstacles(*map_, scan, p, ObstacleOptions());
    EXPECT_EQ(l.unclassified, 2u) << bad;
    EXPECT_EQ(l.label[0], PointClass::kUnknown) << bad;
    p = pose_;
    p.yaw = std::numeric_limits<double>::quiet_NaN();
    EXPECT_EQ(classifyObstacles(*map_, scan, p, ObstacleOptions()).unclassified, 2u);
  }
}

}  // namespace
}  // namespace gmm_localization
