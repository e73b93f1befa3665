// rasterizeRegion on a small map written by MapBuilder: it returns exactly the chunks the
// planner names around the centres, each equal to a rasterization from the whole map, on one
// thread or several; it loads only the tiles the read rule names (a corrupt tile elsewhere does
// not matter, one of those fails with its file name); it rejects invalid raster options.
#include "gmm_localization/core/raster/raster_region.h"

#include <set>

#include <gtest/gtest.h>

#include "gmm_localization/core/raster/rasterizer.h"
#include "support/test_map.h"

namespace gmm_localization {
namespace {

class RegionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testmap::tempDirectory("region");
    const Status s = testmap::build(dir_);
    ASSERT_TRUE(s.ok()) << s.error();
    auto store = MapStore::open(dir_);
    ASSERT_TRUE(store.ok()) << store.error();
    store_ = std::make_unique<MapStore>(std::move(*store));
  }
  void TearDown() override { testmap::removeDirectory(dir_); }

  ChunkPlanner planner() const {
    return ChunkPlanner(store_->geometry(), options_, store_->tileIds());
  }
  std::set<TileId> tilesFor(const std::vector<ChunkId>& chunks) const {
    std::set<TileId> out;
    for (const ChunkId& c : chunks) {
      for (const TileId& t : planner().tilesFor(c)) out.insert(t);
    }
    return out;
  }

  std::string dir_;
  std::unique_ptr<MapStore> store_;
  RasterOptions options_ = testmap::rasterOptions();
  // Chunks (0..2, -1..2) or so: they read tiles x 0..3, not the map's last column (x = 4).
  const std::vector<PlanCentre> centres_{PlanCentre(1.0, 2.0), PlanCentre(4.0, 9.0)};
  const double radius_m_ = 5.0;
};

TEST_F(RegionTest, ReturnsThePlannedChunksEqualToAWholeMapRasterization) {
  auto all = store_->loadAll();
  ASSERT_TRUE(all.ok()) << all.error();
  const std::vector<ChunkId> needed = planner().needed(centres_, radius_m_);
  ASSERT_GE(needed.size(), 4u);
  for (int threads : {1, 3}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    RegionStats stats;
    auto region = rasterizeRegion(*store_, options_, centres_, radius_m_, threads, &stats);
    ASSERT_TRUE(region.ok()) << region.error();
    std::set<ChunkId> got;
    for (const auto& kv : region->chunks()) got.insert(kv.first);
    EXPECT_EQ(got, std::set<ChunkId>(needed.begin(), needed.end()));
    for (const ChunkId& id : needed) {
      const MapChunkConstPtr chunk = region->find(id);
      ASSERT_NE(chunk, nullptr);
      auto want = rasterizeChunk(*all, id, options_);
      ASSERT_TRUE(want.ok());
      EXPECT_TRUE(chunk->sameTables(**want)) << "chunk " << id.x << ", " << id.y;
      EXPECT_EQ(chunk->mixtures(), (*want)->mixtures());
    }
    EXPECT_EQ(stats.chunks, needed.size());
    EXPECT_EQ(stats.tiles, tilesFor(needed).size());
    EXPECT_EQ(stats.bytes, region->bytes());
    EXPECT_GE(stats.load_seconds, 0.0);
    EXPECT_GE(stats.raster_seconds, 0.0);
    EXPECT_EQ(region->options().chunk_shift, options_.chunk_shift);
    EXPECT_EQ(region->geometry().tile_size_cells, store_->geometry().tile_size_cells);
  }
}

TEST_F(RegionTest, LoadsOnlyTheTilesTheRuleNames) {
  const std::vector<ChunkId> needed = planner().needed(centres_, radius_m_);
  const std::set<TileId> named = tilesFor(needed);
  const std::vector<TileId> present = store_->tileIds();
  const TileId* outside = nullptr;
  const TileId* inside = nullptr;
  for (const TileId& t : present) {
    if (named.count(t) == 0 && outside == nullptr) outside = &t;
    if (named.count(t) > 0 && inside == nullptr) inside = &t;
  }
  ASSERT_NE(outside, nullptr) << "the region should not need the whole map";
  ASSERT_NE(inside, nullptr);

  const TileInfo* info = store_->tileInfo(*outside);
  ASSERT_NE(info, nullptr);
  ASSERT_TRUE(testmap::corruptFile(dir_ + "/" + info->file_name));
  auto region = rasterizeRegion(*store_, options_, centres_, radius_m_);
  EXPECT_TRUE(region.ok()) << region.error();

  info = store_->tileInfo(*inside);
  ASSERT_NE(info, nullptr);
  ASSERT_TRUE(testmap::corruptFile(dir_ + "/" + info->file_name));
  region = rasterizeRegion(*store_, options_, centres_, radius_m_);
  ASSERT_FALSE(region.ok());
  EXPECT_NE(region.error().find(info->file_name), std::string::npos) << region.error();
}

TEST_F(RegionTest, FarFromTheMapGivesAnEmptyRegion) {
  RegionStats stats;
  auto region = rasterizeRegion(*store_, options_, {PlanCentre(500.0, -400.0)}, 10.0, 2, &stats);
  ASSERT_TRUE(region.ok()) << region.error();
  EXPECT_EQ(region->size(), 0u);
  EXPECT_EQ(stats.tiles, 0u);
  EXPECT_EQ(stats.chunks, 0u);
  region = rasterizeRegion(*store_, options_, {}, 10.0);
  ASSERT_TRUE(region.ok()) << region.error();
  EXPECT_EQ(region->size(), 0u);
}

TEST_F(RegionTest, RejectsInvalidRasterOptions) {
  RasterOptions bad = options_;
  bad.num_layers = 7;  // blocks larger than a 32-cell chunk
  auto region = rasterizeRegion(*store_, bad, centres_, radius_m_);
  ASSERT_FALSE(region.ok());
  EXPECT_EQ(region.error().rfind("raster options: ", 0), 0u) << region.error();
}

}  // namespace
}  // namespace gmm_localization
