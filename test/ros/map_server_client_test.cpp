// The subscriber side of the map server's protocol (map_server_client.h): chunks and indices in
// any delivery order, eviction by a newer index, map versions,.
#include "gmm_localization/ros/map_server_client.h"

#include <gtest/gtest.h>
#include <boost/make_shared.hpp>

#include "gmm_localization/core/raster/rasterizer.h"
#include "gmm_localization/ros/chunk_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

RasterOptions options() {
  RasterOptions o;
  o.chunk_shift = 4;
  o.num_layers = 2;
  return o;
}

GmmMap smallMap() {
  MapGeometry g;
  g.tile_size_cells = 16;
  GmmMap map(g);
  for (int tx = 0; tx < 2; ++tx) {
    auto tile = std::make_shared<GmmTile>(TileId{tx, 0}, 16);
    for (int y = 0; y < 16; ++y) {
      for (int x = 0; x < 16; ++x) {
        GaussianMixture1D m;
        m.add({1.f, 0.1f * x, 0.05f});
        tile->at(x, y) = m;
      }
    }
    map.insert(tile);
  }
  return map;
}

RasterChunk::ConstPtr chunkMsg(ChunkId id, uint64_t version, double stamp_s) {
  auto chunk = rasterizeChunk(smallMap(), id, options());
  EXPECT_TRUE(chunk.ok());
  auto msg = boost::make_shared<RasterChunk>();
  toMsg(**chunk, version, "map", ros::Time(stamp_s), *msg);
  return msg;
}

MapIndex::ConstPtr indexMsg(uint64_t version, double stamp_s, std::vector<ChunkId> ids) {
  auto index = boost::make_shared<MapIndex>();
  index->header.stamp = ros::Time(stamp_s);
  index->map_version = version;
  index->resolution_m = 0.2;
  index->tile_size_cells = 16;
  const RasterOptions o = options();
  index->z_step_m = o.z_step_m;
  index->ll_floor = o.ll_floor;
  index->ll_ceiling = o.ll_ceiling;
  index->num_layers = o.num_layers;
  index->z_coarsening_period = o.z_coarsening_period;
  index->chunk_shift = o.chunk_shift;
  for (const ChunkId& id : ids) {
    index->chunk_x.push_back(id.x);
    index->chunk_y.push_back(id.y);
  }
  return index;
}

using V = MapServerClient::ChunkVerdict;

TEST(MapServerClient, ChunksBeforeTheirIndexAreKept) {
  MapServerClient c;
  EXPECT_EQ(c.onChunk(chunkMsg({0, 0}, 5, 1.0)), V::kAdded);
  EXPECT_EQ(c.chunks().size(), 0u) << "waiting for the index";
  EXPECT_EQ(c.onIndex(indexMsg(5, 0.5, {})), 0u) << "an older index does not evict it";
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_EQ(c.onIndex(indexMsg(5, 1.5, {{0, 0}})), 0u);
  EXPECT_TRUE(c.complete());
  EXPECT_EQ(c.chunks().geometry().tile_size_cells, 16);
  EXPECT_EQ(c.chunks().options().chunk_shift, 4);
  EXPECT_NE(c.chunks().find({0, 0}), nullptr);
}

TEST(MapServerClient, NewerIndexEvictsOlderChunkOnly) {
  MapServerClient c;
  c.onIndex(indexMsg(5, 1.0, {}));
  EXPECT_EQ(c.onChunk(chunkMsg({0, 0}, 5, 2.0)), V::kAdded);
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 5, 3.0)), V::kAdded);
  // Index at 2.5 lists (0, 0) only: (1, 0) is newer than it and stays.
  EXPECT_EQ(c.onIndex(indexMsg(5, 2.5, {{0, 0}})), 0u);
  EXPECT_EQ(c.chunks().size(), 2u);
  // Index at 4 lists (1, 0) only: (0, 0) was evicted.
  EXPECT_EQ(c.onIndex(indexMsg(5, 4.0, {{1, 0}})), 1u);
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_EQ(c.chunks().find({0, 0}), nullptr);
  // A re-sent copy of the evicted chunk (stamped before the index) is ignored.
  std::string why;
  EXPECT_EQ(c.onChunk(chunkMsg({0, 0}, 5, 2.0), &why), V::kStale);
  EXPECT_FALSE(why.empty());
  EXPECT_EQ(c.chunks().size(), 1u);
}

TEST(MapServerClient, MapVersionsSwitchCleanly) {
  MapServerClient c;
  c.onIndex(indexMsg(5, 1.0, {{0, 0}}));
  c.onChunk(chunkMsg({0, 0}, 5, 0.9));
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 6, 2.0)), V::kAdded);  // a newer map, index not yet here
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 4, 2.0)), V::kStale);
  EXPECT_EQ(c.onIndex(indexMsg(6, 1.5, {{1, 0}})), 1u);
  EXPECT_EQ(c.mapVersion(), 6u);
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_NE(c.chunks().find({1, 0}), nullptr);
  EXPECT_EQ(c.onIndex(indexMsg(5, 9.0, {})), 0u) << "an index of an older version is ignored";
  EXPECT_EQ(c.mapVersion(), 6u);
}

TEST(MapServerClient, InvalidChunksAreRejected) {
  MapServerClient c;
  c.onIndex(indexMsg(5, 1.0, {}));
  auto bad = boost::make_shared<RasterChunk>(*chunkMsg({0, 0}, 5, 2.0));
  bad->layers[0].values_start = bad->values.size() + 1;
  std::string why;
  EXPECT_EQ(c.onChunk(bad, &why), V::kInvalid);
  EXPECT_NE(why.find("overruns"), std::string::npos) << why;
  auto other_shift = boost::make_shared<RasterChunk>(*chunkMsg({0, 0}, 5, 2.0));
  other_shift->shift = 5;  // 32 x 32 cells would need 4x the spans: fromMsg rejects it
  EXPECT_EQ(c.onChunk(other_shift, &why), V::kInvalid);
  EXPECT_EQ(c.chunks().size(), 0u);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
