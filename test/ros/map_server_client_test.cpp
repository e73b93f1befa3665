// The subscriber side of the map server's protocol (map_server_client.h): chunks and indices in
// any delivery order, eviction by a newer index, map versions, malformed indices, and one map
// server at a time (a foreign publisher never outranks the adopted one while it speaks).
#include "gmm_localization/ros/map_server_client.h"

#include <cmath>
#include <cstdint>

#include <gtest/gtest.h>
#include <boost/make_shared.hpp>

#include "../unit/support/small_map.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "gmm_localization/ros/chunk_conversion.h"

namespace gmm_localization {
namespace node {
namespace {

using testing::smallMap;
using testing::smallMapRasterOptions;

RasterChunk::ConstPtr chunkMsg(ChunkId id, uint64_t version, double stamp_s) {
  auto chunk = rasterizeChunk(smallMap(), id, smallMapRasterOptions());
  EXPECT_TRUE(chunk.ok());
  auto msg = boost::make_shared<RasterChunk>();
  toMsg(**chunk, version, "map", ros::Time(stamp_s), *msg);
  return msg;
}

MapIndex::ConstPtr indexMsg(uint64_t version, double stamp_s, std::vector<ChunkId> ids) {
  auto index = boost::make_shared<MapIndex>();
  index->header.stamp = ros::Time(stamp_s);
  index->map_version = version;
  toMsg(testing::smallMapGeometry(), smallMapRasterOptions(), *index);
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

/// A copy of a valid index after `mutate`.
template <typename F>
MapIndex::ConstPtr mutatedIndex(uint64_t version, double stamp_s, F mutate) {
  auto index = boost::make_shared<MapIndex>(*indexMsg(version, stamp_s, {{0, 0}}));
  mutate(*index);
  return index;
}

TEST(MapServerClient, MalformedIndexNeverReplacesTheAdoptedOne) {
  MapServerClient c;
  ASSERT_EQ(c.onIndex(indexMsg(1, 1.0, {{0, 0}})), 0u);
  ASSERT_EQ(c.onChunk(chunkMsg({0, 0}, 1, 2.0)), V::kAdded);
  ASSERT_TRUE(c.complete());
  // The reported case: a huge map_version with resolution 0.
  std::string why;
  EXPECT_EQ(
      c.onIndex(mutatedIndex(~uint64_t{0}, 3.0, [](MapIndex& m) { m.resolution_m = 0.0; }), &why),
      0u);
  EXPECT_NE(why.find("rejected"), std::string::npos) << why;
  EXPECT_NE(why.find("resolution_m"), std::string::npos) << why;
  EXPECT_EQ(c.mapVersion(), 1u);
  EXPECT_EQ(c.rejectedIndices(), 1u);
  EXPECT_TRUE(c.complete());
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_EQ(c.chunks().geometry().resolution_m, 0.2);
  // The real server keeps working: its chunks and its next index are accepted.
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 1, 4.0)), V::kAdded);
  EXPECT_EQ(c.onIndex(indexMsg(1, 5.0, {{0, 0}, {1, 0}}), &why), 0u);
  EXPECT_TRUE(why.empty()) << why;
  EXPECT_EQ(c.chunks().size(), 2u);
  EXPECT_TRUE(c.complete());

  // Each field checked (all with a newer version than the adopted one).
  struct Case {
    const char* what;
    void (*mutate)(MapIndex&);
  };
  const Case cases[] = {
      {"resolution_m", [](MapIndex& m) { m.resolution_m = 5e-4; }},
      {"resolution_m", [](MapIndex& m) { m.resolution_m = std::nan(""); }},
      {"resolution_m", [](MapIndex& m) { m.resolution_m = 1e6; }},
      {"tile_size_cells", [](MapIndex& m) { m.tile_size_cells = 0; }},
      {"tile_size_cells", [](MapIndex& m) { m.tile_size_cells = 1 << 30; }},
      {"origin", [](MapIndex& m) { m.origin_x_m = INFINITY; }},
      {"origin", [](MapIndex& m) { m.origin_y_m = 1e15; }},
      {"num_layers", [](MapIndex& m) { m.num_layers = 1000; }},
      {"num_layers", [](MapIndex& m) { m.num_layers = -1; }},
      {"chunk_shift", [](MapIndex& m) { m.chunk_shift = 31; }},
      {"z_step_m", [](MapIndex& m) { m.z_step_m = 0.0; }},
      {"z_coarsening_period", [](MapIndex& m) { m.z_coarsening_period = -5; }},
      {"ll_floor", [](MapIndex& m) { m.ll_floor = std::nan(""); }},
      {"chunk_x lists", [](MapIndex& m) { m.chunk_y.push_back(3); }},
      {"lies beyond", [](MapIndex& m) { m.chunk_x[0] = INT32_MAX; }},
      {"lies beyond", [](MapIndex& m) { m.chunk_y[0] = INT32_MIN; }},
      {"map extent", [](MapIndex& m) { m.max_x_m = std::nan(""); }},
      {"map extent", [](MapIndex& m) { m.min_y_m = -1e12; }},
      {"min > max", [](MapIndex& m) { m.min_x_m = 10.0; }},
  };
  size_t rejected = c.rejectedIndices();
  for (const Case& k : cases) {
    EXPECT_EQ(c.onIndex(mutatedIndex(2, 6.0, k.mutate), &why), 0u) << k.what;
    EXPECT_NE(why.find(k.what), std::string::npos) << k.what << ": " << why;
    EXPECT_EQ(c.rejectedIndices(), ++rejected) << k.what;
    EXPECT_FALSE(validateIndex(*mutatedIndex(2, 6.0, k.mutate)).empty()) << k.what;
  }
  EXPECT_EQ(c.mapVersion(), 1u);
  EXPECT_EQ(c.chunks().size(), 2u);
  EXPECT_TRUE(validateIndex(*indexMsg(2, 6.0, {{-5, 7}})).empty());
  EXPECT_EQ(c.onIndex(nullptr, &why), 0u);
  EXPECT_FALSE(why.empty());
}

/// A copy of `msg` with a map version of its own (as a foreign publisher would send).
RasterChunk::ConstPtr withVersion(const RasterChunk::ConstPtr& msg, uint64_t version) {
  auto copy = boost::make_shared<RasterChunk>(*msg);
  copy->map_version = version;
  return copy;
}

ros::WallTime wall(double s) { return ros::WallTime(s); }

TEST(MapServerClient, WellFormedForeignIndexNeverOutranksTheAdoptedServer) {
  const std::string server = "/localization/localization_manager", intruder = "/intruder";
  MapServerClient c(5.0);
  ASSERT_EQ(c.onIndex(indexMsg(1, 1.0, {{0, 0}}), server, wall(100.0)), 0u);
  ASSERT_EQ(c.onChunk(chunkMsg({0, 0}, 1, 2.0), server, wall(100.1)), V::kAdded);
  ASSERT_TRUE(c.complete());
  EXPECT_EQ(c.publisher(), server);

  // One valid index from another publisher, with a far newer version: ignored, with a reason.
  std::string why;
  ASSERT_TRUE(validateIndex(*indexMsg(~uint64_t{0} - 1, 3.0, {{1, 0}})).empty());
  EXPECT_EQ(c.onIndex(indexMsg(~uint64_t{0} - 1, 3.0, {{1, 0}}), intruder, wall(101.0), &why), 0u);
  EXPECT_NE(why.find("ignored"), std::string::npos) << why;
  EXPECT_NE(why.find(intruder), std::string::npos) << why;
  EXPECT_NE(why.find(server), std::string::npos) << why;
  EXPECT_EQ(c.lastIgnoredReason(), why);
  EXPECT_EQ(c.ignoredIndices(), 1u);
  EXPECT_EQ(c.rejectedIndices(), 0u) << "well-formed: ignored, not rejected";
  EXPECT_EQ(c.mapVersion(), 1u);
  EXPECT_EQ(c.publisher(), server);
  EXPECT_TRUE(c.complete());
  EXPECT_EQ(c.chunks().size(), 1u);
  // Its chunks are refused too, whatever their version.
  EXPECT_EQ(c.onChunk(withVersion(chunkMsg({1, 0}, 1, 3.5), ~uint64_t{0} - 1), intruder,
                      wall(101.5), &why),
            V::kInvalid);
  EXPECT_NE(why.find("not from the adopted map server"), std::string::npos) << why;
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 1, 3.6), intruder, wall(101.6), &why), V::kInvalid);
  EXPECT_EQ(c.chunks().size(), 1u);

  // The adopted server goes on: its chunks and indices are taken as before.
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 1, 4.0), server, wall(102.0)), V::kAdded);
  EXPECT_EQ(c.onIndex(indexMsg(1, 5.0, {{0, 0}, {1, 0}}), server, wall(102.5), &why), 0u);
  EXPECT_TRUE(why.empty()) << why;
  EXPECT_EQ(c.chunks().size(), 2u);
  EXPECT_TRUE(c.complete());
  // Within publisher_timeout_s of the server's last word, every foreign index is ignored.
  EXPECT_EQ(c.onIndex(indexMsg(7, 6.0, {}), intruder, wall(107.0), &why), 0u);
  EXPECT_EQ(c.ignoredIndices(), 2u);
  EXPECT_EQ(c.mapVersion(), 1u);
  EXPECT_EQ(c.publisherSwitches(), 0u);
}

TEST(MapServerClient, AnotherPublisherTakesOverOnlyAfterTheAdoptedOneFellSilent) {
  const std::string old_server = "/old_manager", new_server = "/new_manager";
  MapServerClient c(5.0);
  ASSERT_EQ(c.onIndex(indexMsg(9, 1.0, {{0, 0}, {1, 0}}), old_server, wall(100.0)), 0u);
  ASSERT_EQ(c.onChunk(chunkMsg({0, 0}, 9, 0.5), old_server, wall(100.0)), V::kAdded);
  ASSERT_EQ(c.onChunk(chunkMsg({1, 0}, 9, 0.6), old_server, wall(100.0)), V::kAdded);
  ASSERT_TRUE(c.complete());
  // The old server is gone (silent 6 s): the new one's chunks may wait for its index, whose
  // version may even be older than the old server's.
  EXPECT_EQ(c.onChunk(chunkMsg({1, 0}, 3, 0.2), new_server, wall(106.0)), V::kAdded);
  EXPECT_EQ(c.chunks().size(), 2u) << "the old map stays until the new index";
  EXPECT_EQ(c.onIndex(indexMsg(3, 0.3, {{1, 0}}), new_server, wall(106.1)), 2u)
      << "the old server's chunks are dropped";
  EXPECT_EQ(c.publisher(), new_server);
  EXPECT_EQ(c.publisherSwitches(), 1u);
  EXPECT_EQ(c.mapVersion(), 3u);
  EXPECT_TRUE(c.complete());
  EXPECT_NE(c.chunks().find({1, 0}), nullptr);
  EXPECT_EQ(c.chunks().find({0, 0}), nullptr);
  // The old server coming back is now the foreign one.
  std::string why;
  EXPECT_EQ(c.onIndex(indexMsg(10, 9.0, {{0, 0}}), old_server, wall(107.0), &why), 0u);
  EXPECT_NE(why.find(old_server), std::string::npos) << why;
  EXPECT_EQ(c.mapVersion(), 3u);
  // The adopted one restarting under its name (a newer version) is simply a new map.
  EXPECT_EQ(c.onIndex(indexMsg(4, 9.5, {}), new_server, wall(108.0)), 1u);
  EXPECT_EQ(c.mapVersion(), 4u);
  EXPECT_EQ(c.publisherSwitches(), 1u);
}

TEST(MapServerClient, PublishersComeFromTheMessageEvents) {
  auto event_index = [](const MapIndex::ConstPtr& m, const std::string& callerid) {
    auto header = boost::make_shared<ros::M_string>();
    (*header)["callerid"] = callerid;
    return ros::MessageEvent<const MapIndex>(m, header, ros::Time(1.0));
  };
  auto event_chunk = [](const RasterChunk::ConstPtr& m, const std::string& callerid) {
    auto header = boost::make_shared<ros::M_string>();
    (*header)["callerid"] = callerid;
    return ros::MessageEvent<const RasterChunk>(m, header, ros::Time(1.0));
  };
  MapServerClient c;
  // A chunk of the foreign publisher waiting before any index is dropped when the server's
  // index is adopted.
  EXPECT_EQ(c.onChunk(event_chunk(chunkMsg({1, 0}, 2, 0.5), "/foreign")), V::kAdded);
  EXPECT_EQ(c.onChunk(event_chunk(chunkMsg({0, 0}, 2, 0.6), "/server")), V::kAdded);
  EXPECT_EQ(c.onIndex(event_index(indexMsg(2, 1.0, {{0, 0}, {1, 0}}), "/server")), 0u);
  EXPECT_EQ(c.publisher(), "/server");
  EXPECT_EQ(c.chunks().size(), 1u);
  EXPECT_EQ(c.chunks().find({1, 0}), nullptr) << "the foreign chunk never entered the map";
  std::string why;
  EXPECT_EQ(c.onIndex(event_index(indexMsg(1000, 2.0, {}), "/foreign"), &why), 0u);
  EXPECT_NE(why.find("/foreign"), std::string::npos) << why;
  EXPECT_EQ(c.mapVersion(), 2u);
  EXPECT_EQ(c.onChunk(event_chunk(chunkMsg({1, 0}, 2, 3.0), "/foreign"), &why), V::kInvalid);
  EXPECT_EQ(c.onChunk(event_chunk(chunkMsg({1, 0}, 2, 3.0), "/server")), V::kAdded);
  EXPECT_TRUE(c.complete());
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
