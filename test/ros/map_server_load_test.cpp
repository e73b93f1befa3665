// The map server's load_map decision (map_server_load.h, what the service answers): a directory
// whose tiles are truncated or CRC-broken is refused, naming the tiles and the reasons, and the
// served map stays; the same directory restored loads, with every tile read afresh. A map of
// the other layer (height / reflectivity) is refused with the build_map option that makes the
// one asked for.
#include "gmm_localization/ros/map_server_load.h"

#include <gtest/gtest.h>

#include "../unit/support/test_map.h"
#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/mapping/map_builder.h"

namespace gmm_localization {
namespace node {
namespace {

class LoadMapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    served_ = testmap::tempDirectory("load_served");
    other_ = testmap::tempDirectory("load_other");
    ASSERT_TRUE(testmap::build(served_).ok());
    ASSERT_TRUE(testmap::build(other_).ok());
    ChunkEngineOptions o;
    o.raster = testmap::rasterOptions();
    o.raster_radius_m = 8.0;
    o.tile_cache_radius_m = 8.0;
    ChunkEngine::Callbacks cb;
    cb.on_chunk = [](const MapChunkConstPtr& c, uint64_t) { return c; };
    auto e = ChunkEngine::create(served_, o, cb, 40);
    ASSERT_TRUE(e.ok()) << e.error();
    engine_ = std::move(*e);
    engine_->setCentres({PlanCentre(10.0, 5.0)});
  }
  void TearDown() override {
    engine_.reset();
    testmap::removeDirectory(served_);
    testmap::removeDirectory(other_);
  }

  std::string tilePath(const std::string& dir, const TileId& id) {
    auto store = MapStore::open(dir);
    EXPECT_TRUE(store.ok());
    const TileInfo* info = store->tileInfo(id);
    EXPECT_NE(info, nullptr);
    return dir + "/" + (info ? info->file_name : std::string("?"));
  }

  void expectStillServing() {
    EXPECT_EQ(engine_->mapVersion(), 40u);
    EXPECT_EQ(engine_->store()->directory(), served_);
  }

  std::string served_, other_;
  std::unique_ptr<ChunkEngine> engine_;
};

TEST_F(LoadMapTest, CrcBrokenAndTruncatedTilesRefuseTheMapNamingThem) {
  ASSERT_TRUE(testmap::corruptFile(tilePath(other_, {3, 1})));
  const std::string truncated_path = tilePath(other_, {0, 2});
  auto bytes = readFileBytes(truncated_path);
  ASSERT_TRUE(bytes.ok());
  const std::vector<uint8_t> original = *bytes;
  ASSERT_TRUE(
      writeFileAtomic(truncated_path, std::vector<uint8_t>(original.begin(), original.begin() + 20))
          .ok());

  const LoadMapOutcome refused = loadMapDirectory(*engine_, other_);
  EXPECT_FALSE(refused.success);
  const std::string& m = refused.message;
  EXPECT_NE(m.find("kept map '" + served_ + "'"), std::string::npos) << m;
  EXPECT_NE(m.find(other_), std::string::npos) << m;
  EXPECT_NE(m.find("2 of "), std::string::npos) << m;
  EXPECT_NE(m.find("tile (3, 1)"), std::string::npos) << m;
  EXPECT_NE(m.find("CRC"), std::string::npos) << m;
  EXPECT_NE(m.find("tile (0, 2)"), std::string::npos) << m;
  EXPECT_NE(m.find("truncated"), std::string::npos) << m;
  expectStillServing();

  // At most max_listed tiles are named; the rest are counted.
  const LoadMapOutcome short_list = loadMapDirectory(*engine_, other_, 1);
  EXPECT_FALSE(short_list.success);
  EXPECT_NE(short_list.message.find("and 1 more"), std::string::npos) << short_list.message;

  // Restored, the same directory loads: a new map version.
  ASSERT_TRUE(writeFileAtomic(truncated_path, original).ok());
  EXPECT_FALSE(loadMapDirectory(*engine_, other_).success) << "(3, 1) is still broken";
  ASSERT_TRUE(testmap::corruptFile(tilePath(other_, {3, 1})));  // flips the byte back
  const LoadMapOutcome loaded = loadMapDirectory(*engine_, other_);
  EXPECT_TRUE(loaded.success) << loaded.message;
  EXPECT_NE(loaded.message.find("map_version 41"), std::string::npos) << loaded.message;
  EXPECT_EQ(engine_->mapVersion(), 41u);
  EXPECT_EQ(engine_->store()->directory(), other_);
  ASSERT_TRUE(engine_->waitIdle(30.0));
  EXPECT_TRUE(engine_->stats().tile_errors.empty());
}

TEST_F(LoadMapTest, MissingDirectoryOrTileFileIsRefused) {
  const LoadMapOutcome missing = loadMapDirectory(*engine_, "/nonexistent/gmm_map");
  EXPECT_FALSE(missing.success);
  EXPECT_NE(missing.message.find("/nonexistent/gmm_map"), std::string::npos) << missing.message;
  ASSERT_EQ(std::remove(tilePath(other_, {1, 1}).c_str()), 0);
  const LoadMapOutcome no_file = loadMapDirectory(*engine_, other_);
  EXPECT_FALSE(no_file.success);
  EXPECT_NE(no_file.message.find("tile (1, 1)"), std::string::npos) << no_file.message;
  expectStillServing();
}

/// A small reflectivity map: a flat road of asphalt with a painted stripe, seen from a vehicle
/// at its centre.
Status buildReflectivityMap(const std::string& directory) {
  MapBuilderOptions o;
  o.output_directory = directory;
  o.overwrite = true;
  o.geometry = testmap::geometry();
  o.threads = 1;
  o.spill_buffer_bytes = size_t{4} << 20;
  o.layer = MapLayer::kReflectivity;
  auto builder = MapBuilder::create(o);
  if (!builder) return Status::failure(builder.error());
  PointBatch batch;
  batch.has_vehicle_origin = true;
  batch.vehicle_origin_m = Eigen::Vector3d(10.0, 5.0, 0.0);
  for (float x = 0.f; x < 20.f; x += 0.05f) {
    for (float y = 0.f; y < 10.f; y += 0.05f) {
      batch.points_m.emplace_back(x, y, 0.f);
      batch.intensity.push_back(std::abs(y - 5.f) < 0.1f ? 110.f : 11.f);
    }
  }
  if (Status s = (*builder)->addBatch(batch); !s) return s;
  auto stats = (*builder)->finish();
  return stats ? Status::success() : Status::failure(stats.error());
}

TEST_F(LoadMapTest, AMapOfTheOtherLayerIsRefusedNamingTheBuildMapOption) {
  const std::string reflectivity = testmap::tempDirectory("load_reflectivity");
  ASSERT_TRUE(buildReflectivityMap(reflectivity).ok());
  auto height_store = MapStore::open(other_);
  auto reflectivity_store = MapStore::open(reflectivity);
  ASSERT_TRUE(height_store.ok() && reflectivity_store.ok());
  EXPECT_EQ(layerProblem(*height_store, MapLayer::kHeight), "");
  EXPECT_EQ(layerProblem(*reflectivity_store, MapLayer::kReflectivity), "");
  const std::string no_layer = layerProblem(*height_store, MapLayer::kReflectivity);
  EXPECT_NE(no_layer.find("build_map --layer reflectivity"), std::string::npos) << no_layer;
  EXPECT_NE(no_layer.find(other_), std::string::npos) << no_layer;
  EXPECT_NE(layerProblem(*reflectivity_store, MapLayer::kHeight).find("method:=reflectivity"),
            std::string::npos);

  // load_map: a height map asked for as reflectivity, and the reverse, keep the served map.
  const LoadMapOutcome wrong = loadMapDirectory(*engine_, other_, 5, MapLayer::kReflectivity);
  EXPECT_FALSE(wrong.success);
  EXPECT_NE(wrong.message.find("holds the height layer"), std::string::npos) << wrong.message;
  const LoadMapOutcome reverse = loadMapDirectory(*engine_, reflectivity);
  EXPECT_FALSE(reverse.success);
  EXPECT_NE(reverse.message.find("holds the reflectivity layer"), std::string::npos)
      << reverse.message;
  expectStillServing();
  // A missing MAP/reflectivity says how to build it.
  const LoadMapOutcome missing =
      loadMapDirectory(*engine_, other_ + "/reflectivity", 5, MapLayer::kReflectivity);
  EXPECT_FALSE(missing.success);
  EXPECT_NE(
      missing.message.find("build_map --layer reflectivity --output " + other_ + "/reflectivity"),
      std::string::npos)
      << missing.message;
  // The right layer loads.
  EXPECT_TRUE(loadMapDirectory(*engine_, reflectivity, 5, MapLayer::kReflectivity).success);
  engine_.reset();
  testmap::removeDirectory(reflectivity);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
