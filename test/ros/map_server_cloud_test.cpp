// The map_cloud visualisation (map_server_cloud.h): one point per non-empty cell near the
// vehicle, at the mean of its heaviest component, coloured by the number of components.
#include "gmm_localization/ros/map_server_cloud.h"

#include <cmath>

#include <gtest/gtest.h>

#include "../unit/support/small_map.h"
#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace node {
namespace {

using testing::smallMap;
using testing::smallMapRasterOptions;

TEST(MapCloud, OnePointPerNonEmptyCellNearTheCentre) {
  GmmMap map = smallMap();
  // One two-component cell: heaviest component chosen.
  auto tile = std::make_shared<GmmTile>(*map.tile({0, 0}));
  GaussianMixture1D two;
  two.add({0.3f, 0.0f, 0.05f});
  two.add({0.7f, 2.0f, 0.2f});
  tile->at(3, 2) = two;
  tile->at(4, 2).clear();
  map.insert(tile);
  const RasterOptions o = smallMapRasterOptions();
  std::vector<MapChunkConstPtr> chunks{*rasterizeChunk(map, {0, 0}, o),
                                       *rasterizeChunk(map, {1, 0}, o)};
  CloudData cloud;
  std::vector<float> sigma;
  // Radius 0.5 m around the centre of cell (3, 2) = (0.7, 0.5): cells within 0.5 m.
  buildMapCloud(chunks, map.geometry(), {PlanCentre(0.7, 0.5)}, 0.5, cloud, sigma);
  ASSERT_EQ(cloud.points.size(), sigma.size());
  ASSERT_EQ(cloud.points.size(), cloud.intensity.size());
  // Cells whose centres lie within 0.5 m of (0.7, 0.5), minus the empty cell (4, 2): 21 - 1.
  EXPECT_EQ(cloud.points.size(), 20u);
  bool found = false;
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    if (std::abs(cloud.points[i].x() - 0.7f) < 1e-4f &&
        std::abs(cloud.points[i].y() - 0.5f) < 1e-4f) {
      found = true;
      EXPECT_FLOAT_EQ(cloud.points[i].z(), 2.0f);
      EXPECT_FLOAT_EQ(cloud.intensity[i], 2.0f);
      EXPECT_FLOAT_EQ(sigma[i], 0.2f);
    } else {
      EXPECT_FLOAT_EQ(cloud.intensity[i], 1.0f);
    }
  }
  EXPECT_TRUE(found);
  buildMapCloud(chunks, map.geometry(), {}, 100.0, cloud, sigma);
  EXPECT_TRUE(cloud.points.empty());
  buildMapCloud(chunks, map.geometry(), {PlanCentre(0, 0)}, 100.0, cloud, sigma);
  EXPECT_EQ(cloud.points.size(), 2u * 16 * 16 - 1);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
