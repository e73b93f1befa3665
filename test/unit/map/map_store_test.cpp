#include "gmm_localization/core/map/map_store.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "support/temp_dir.h"

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;

/// A map of 3 x 2 tiles (ids x in {-1, 0, 1}, y in {0, 1}) of 10 cells at 1 m, written by hand.
struct SmallMap {
  SmallMap() {
    MapManifest m;
    m.geometry.resolution_m = 1.0;
    m.geometry.tile_size_cells = 10;
    m.geometry.origin_x_m = 100.0;
    m.geometry.origin_y_m = -50.0;
    m.provenance = "map_store_test";
    for (int tx = -1; tx <= 1; ++tx) {
      for (int ty = 0; ty <= 1; ++ty) {
        GmmTile t({tx, ty}, 10);
        t.at(0, 0).add({1.f, float(tx), 0.1f});  // one component
        t.at(5, 5).add({0.6f, 0.f, 0.05f});      // two components
        t.at(5, 5).add({0.4f, 4.f + float(ty), 1.f});
        auto enc = encodeTile(t);
        EXPECT_TRUE(enc.ok());
        EXPECT_TRUE(writeFileAtomic(dir + "/" + enc->info.file_name, enc->bytes).ok());
        m.tiles.push_back(enc->info);
      }
    }
    EXPECT_TRUE(writeManifest(dir, m).ok());
  }
  testing::TempDir tmp{"gmm_map_store"};
  std::string dir = tmp.path;
};

TEST(MapStore, OpensListsAndLoads) {
  SmallMap sm;
  auto store = MapStore::open(sm.dir);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->geometry().origin_x_m, 100.0);
  EXPECT_EQ(store->manifest().provenance, "map_store_test");
  const auto ids = store->tileIds();
  ASSERT_EQ(ids.size(), 6u);
  EXPECT_EQ(ids.front(), (TileId{-1, 0}));
  EXPECT_EQ(ids.back(), (TileId{1, 1}));
  EXPECT_TRUE(store->hasTile({0, 1}));
  EXPECT_FALSE(store->hasTile({2, 0}));
  EXPECT_EQ(store->tileInfo({2, 0}), nullptr);
  auto tile = store->loadTile({1, 1});
  ASSERT_TRUE(tile.ok()) << tile.error();
  EXPECT_EQ((*tile)->id(), (TileId{1, 1}));
  EXPECT_EQ((*tile)->at(5, 5).size(), 2);
  EXPECT_NEAR((*tile)->at(5, 5).component(1).mean_m, 5.0, 1e-3);
  auto missing = store->loadTile({7, 7});
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("no tile (7, 7)"), std::string::npos);
}

TEST(MapStore, TilesWithinRadius) {
  SmallMap sm;
  auto store = MapStore::open(sm.dir);
  ASSERT_TRUE(store.ok());
  // Tile (0, 0) covers x in [100, 110), y in [-50, -40).
  EXPECT_EQ(store->tilesWithin(105.0, -45.0, 0.0), (std::vector<TileId>{{0, 0}}));
  // 4 m reaches tile (0, 1) (y >= -40) only: tiles -1 and 1 are 5 m away in x.
  EXPECT_EQ(store->tilesWithin(105.0, -44.0, 4.0), (std::vector<TileId>{{0, 0}, {0, 1}}));
  // The corner (110, -40) is within 1 m of (110.5, -39.5) for all four tiles around it.
  EXPECT_EQ(store->tilesWithin(110.5, -39.5, 1.0),
            (std::vector<TileId>{{0, 0}, {0, 1}, {1, 0}, {1, 1}}));
  EXPECT_EQ(store->tilesWithin(105.0, -45.0, 1000.0).size(), 6u);
  EXPECT_TRUE(store->tilesWithin(0.0, 0.0, 10.0).empty());
  EXPECT_TRUE(store->tilesWithin(105.0, -45.0, -1.0).empty());
  EXPECT_TRUE(store->tilesWithin(NAN, -45.0, 5.0).empty());
  auto loaded = store->loadTilesWithin(105.0, -44.0, 4.0);
  ASSERT_TRUE(loaded.ok());
  ASSERT_EQ(loaded->size(), 2u);
  EXPECT_EQ((*loaded)[1]->id(), (TileId{0, 1}));
}

TEST(MapStore, SummaryFromManifest) {
  SmallMap sm;
  auto store = MapStore::open(sm.dir);
  ASSERT_TRUE(store.ok());
  const MapSummary s = store->summary();
  EXPECT_EQ(s.tiles, 6u);
  EXPECT_EQ(s.cells(), 600u);
  EXPECT_EQ(s.cells_by_components[1], 6u);
  EXPECT_EQ(s.cells_by_components[2], 6u);
  EXPECT_EQ(s.nonEmptyCells(), 12u);
  EXPECT_EQ(s.min_x_m, 90.0);
  EXPECT_EQ(s.max_x_m, 120.0);
  EXPECT_EQ(s.min_y_m, -50.0);
  EXPECT_EQ(s.max_y_m, -30.0);
  EXPECT_NEAR(s.z_min_m, -1.4, 1e-3);  // tile -1: mean -1, sigma 0.1
  EXPECT_NEAR(s.z_max_m, 9.0, 1e-3);   // 4 + 1 + 4 * 1
  uint64_t bytes = 0;
  for (const auto& e : fs::directory_iterator(sm.dir)) bytes += fs::file_size(e.path());
  EXPECT_EQ(s.bytesOnDisk(), bytes);
  auto all = store->loadAll();
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->tiles().size(), 6u);
  const GaussianMixture1D* c = all->cell(all->geometry().cellAt(95.5, -34.5));  // tile (-1,1) (5,5)
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->size(), 2);
}

TEST(MapStore, VerifyReportsEveryBrokenTile) {
  SmallMap sm;
  auto store = MapStore::open(sm.dir);
  ASSERT_TRUE(store.ok());
  EXPECT_TRUE(store->verify().empty());
  const std::string flipped = sm.dir + "/" + tileFileName({0, 1});
  {
    std::fstream f(flipped, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(50);
    char c;
    f.read(&c, 1);
    c ^= 0x10;
    f.seekp(50);
    f.write(&c, 1);
  }
  fs::remove(sm.dir + "/" + tileFileName({-1, 0}));
  const auto errors = store->verify();
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("tile_-1_0.gmt': missing"), std::string::npos) << errors[0];
  EXPECT_NE(errors[1].find("tile_0_1.gmt"), std::string::npos) << errors[1];
  EXPECT_NE(errors[1].find("CRC-32 mismatch"), std::string::npos) << errors[1];
  EXPECT_FALSE(store->loadAll().ok());
  EXPECT_FALSE(store->loadTilesWithin(105.0, -44.0, 4.0).ok());
  EXPECT_TRUE(store->loadTile({1, 0}).ok());  // the others still load
}

TEST(MapStore, OpenFailsClearly) {
  auto none = MapStore::open("/nonexistent/gmm_map");
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().find("/nonexistent/gmm_map/manifest.gmm"), std::string::npos);
  SmallMap sm;
  std::ofstream(sm.dir + "/manifest.gmm", std::ios::binary) << "GMMM garbage";
  auto bad = MapStore::open(sm.dir);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("manifest"), std::string::npos);
}

}  // namespace
}  // namespace gmm_localization
