// The map server's background engine on a small map written by MapBuilder: it serves exactly the
// planned chunks, each equal to an in-process rasterizeChunk of the whole map; it evicts what
// the vehicle left; a corrupt tile is skipped and named; a bad map switch keeps the map.
#include "gmm_localization/core/raster/chunk_engine.h"

#include <atomic>
#include <mutex>
#include <set>

#include <gtest/gtest.h>

#include "gmm_localization/core/raster/rasterizer.h"
#include "support/test_map.h"

namespace gmm_localization {
namespace {

class EngineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testmap::tempDirectory("engine");
    const Status s = testmap::build(dir_);
    ASSERT_TRUE(s.ok()) << s.error();
    options_.raster = testmap::rasterOptions();
    options_.raster_radius_m = 8.0;
    options_.tile_cache_radius_m = 8.0;
    options_.hysteresis_m = 4.0;
  }
  void TearDown() override {
    engine_.reset();
    testmap::removeDirectory(dir_);
  }

  void start(int threads = 1, const std::string& dir = {}) {
    options_.worker_threads = threads;
    ChunkEngine::Callbacks cb;
    cb.on_chunk = [this](const MapChunkConstPtr& c, uint64_t version) {
      std::lock_guard<std::mutex> lock(mutex_);
      published_.push_back(c->id());
      versions_.insert(version);
      return c;
    };
    cb.on_held_changed = [this]() { ++held_changes_; };
    cb.on_tile_error = [this](const TileId& t, const std::string& why) {
      std::lock_guard<std::mutex> lock(mutex_);
      tile_errors_.emplace_back(t, why);
    };
    auto e = ChunkEngine::create(dir.empty() ? dir_ : dir, options_, cb, 41);
    ASSERT_TRUE(e.ok()) << e.error();
    engine_ = std::move(*e);
  }

  /// Every held chunk equals rasterizeChunk of `map` (tables and mixtures).
  void expectHeldEqual(const GmmMap& map) {
    for (const MapChunkConstPtr& got : engine_->held()) {
      auto want = rasterizeChunk(map, got->id(), options_.raster);
      ASSERT_TRUE(want.ok());
      ASSERT_TRUE(got->sameTables(**want)) << "chunk " << got->id().x << ", " << got->id().y;
      ASSERT_EQ(got->mixtures(), (*want)->mixtures());
    }
  }

  std::set<ChunkId> heldIds() {
    std::set<ChunkId> ids;
    for (const auto& c : engine_->held()) ids.insert(c->id());
    return ids;
  }

  std::string dir_;
  ChunkEngineOptions options_;
  std::unique_ptr<ChunkEngine> engine_;
  std::mutex mutex_;
  std::vector<ChunkId> published_;
  std::set<uint64_t> versions_;
  std::vector<std::pair<TileId, std::string>> tile_errors_;
  std::atomic<int> held_changes_{0};
};

TEST_F(EngineTest, ServesPlannedChunksEqualToInProcessRasterization) {
  start();
  EXPECT_TRUE(engine_->waitIdle(5.0));
  EXPECT_TRUE(engine_->held().empty()) << "nothing before a position is known";

  const PlanCentre at(10.0, 5.0);
  engine_->setCentres({at});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  auto store = MapStore::open(dir_);
  ASSERT_TRUE(store.ok());
  const ChunkPlanner planner(store->geometry(), options_.raster, store->tileIds());
  const std::vector<ChunkId> needed = planner.needed({at}, options_.raster_radius_m);
  ASSERT_FALSE(needed.empty());
  EXPECT_EQ(heldIds(), std::set<ChunkId>(needed.begin(), needed.end()));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(published_, needed) << "published nearest first, once each";
    EXPECT_EQ(versions_, std::set<uint64_t>({41}));
  }
  auto all = store->loadAll();
  ASSERT_TRUE(all.ok());
  expectHeldEqual(*all);

  const ChunkEngineStats st = engine_->stats();
  EXPECT_EQ(st.chunks_held, needed.size());
  EXPECT_EQ(st.chunks_pending, 0u);
  EXPECT_EQ(st.chunks_rasterized, needed.size());
  EXPECT_GT(st.raster_bytes, 0u);
  EXPECT_GT(st.tiles_cached, 0u);
  EXPECT_TRUE(st.tile_errors.empty());
  EXPECT_GE(held_changes_.load(), static_cast<int>(needed.size()));
}

TEST_F(EngineTest, EvictsWhatTheVehicleLeftWithHysteresis) {
  start();
  engine_->setCentres({PlanCentre(0.0, 5.0)});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  const std::set<ChunkId> first = heldIds();
  ASSERT_FALSE(first.empty());
  // A small move (within the hysteresis): nothing is evicted, new chunks may come.
  engine_->setCentres({PlanCentre(2.0, 5.0)});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  const std::set<ChunkId> second = heldIds();
  for (const ChunkId& id : first) EXPECT_EQ(second.count(id), 1u);
  // A big move: the old chunks beyond radius + hysteresis go, the new ones come.
  const PlanCentre far(22.0, 5.0);
  engine_->setCentres({far});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  auto store = MapStore::open(dir_);
  const ChunkPlanner planner(store->geometry(), options_.raster, store->tileIds());
  for (const ChunkId& id : heldIds()) {
    EXPECT_LE(planner.distanceToChunk(id, far), options_.raster_radius_m + options_.hysteresis_m);
  }
  for (const ChunkId& id : planner.needed({far}, options_.raster_radius_m)) {
    EXPECT_EQ(heldIds().count(id), 1u);
  }
  EXPECT_EQ(heldIds().count(ChunkId{0, 1}), 0u) << "chunk near x = 0 m evicted";
}

TEST_F(EngineTest, TwoWorkersServeTheSameChunks) {
  start(2);
  const PlanCentre at(8.0, 4.0);
  engine_->setCentres({at});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  auto store = MapStore::open(dir_);
  const ChunkPlanner planner(store->geometry(), options_.raster, store->tileIds());
  const auto needed = planner.needed({at}, options_.raster_radius_m);
  EXPECT_EQ(heldIds(), std::set<ChunkId>(needed.begin(), needed.end()));
  expectHeldEqual(*store->loadAll());
}

TEST_F(EngineTest, CorruptTileIsSkippedNamedAndTheRestServed) {
  auto store = MapStore::open(dir_);
  ASSERT_TRUE(store.ok());
  const TileId bad{3, 1};  // a chunk of its own and the reach of chunk (2, 1)
  const TileInfo* info = store->tileInfo(bad);
  ASSERT_NE(info, nullptr);
  ASSERT_TRUE(testmap::corruptFile(dir_ + "/" + info->file_name));

  start(2);
  engine_->setCentres({PlanCentre(10.0, 5.0)});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  const ChunkEngineStats st = engine_->stats();
  ASSERT_EQ(st.tile_errors.size(), 1u);
  EXPECT_EQ(st.tile_errors.begin()->first, bad);
  EXPECT_NE(st.tile_errors.begin()->second.find(info->file_name), std::string::npos)
      << st.tile_errors.begin()->second;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ASSERT_EQ(tile_errors_.size(), 1u) << "reported once";
    EXPECT_EQ(tile_errors_[0].first, bad);
  }
  // Everything planned is served; chunks reading the bad tile see it as empty.
  const ChunkPlanner planner(store->geometry(), options_.raster, store->tileIds());
  const auto needed = planner.needed({PlanCentre(10.0, 5.0)}, options_.raster_radius_m);
  EXPECT_EQ(heldIds(), std::set<ChunkId>(needed.begin(), needed.end()));
  GmmMap without(store->geometry());
  for (const TileId& t : store->tileIds()) {
    if (t != bad) without.insert(*store->loadTile(t));
  }
  expectHeldEqual(without);
}

TEST_F(EngineTest, SwitchMapKeepsTheMapOnFailureAndStartsOverOnSuccess) {
  start();
  engine_->setCentres({PlanCentre(10.0, 5.0)});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  const std::set<ChunkId> before = heldIds();
  ASSERT_FALSE(before.empty());

  const Status missing = engine_->switchMap("/nonexistent/gmm_map");
  EXPECT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("/nonexistent/gmm_map"), std::string::npos) << missing.error();
  EXPECT_FALSE(engine_->switchMap("").ok());
  EXPECT_EQ(engine_->mapVersion(), 41u);
  EXPECT_EQ(heldIds(), before);

  const std::string other = testmap::tempDirectory("engine_other");
  ASSERT_TRUE(testmap::build(other).ok());
  ASSERT_TRUE(engine_->switchMap(other).ok());
  EXPECT_EQ(engine_->mapVersion(), 42u);
  EXPECT_EQ(engine_->store()->directory(), other);
  ASSERT_TRUE(engine_->waitIdle(30.0));
  EXPECT_EQ(heldIds(), before) << "same position, same chunks, re-rasterized";
  EXPECT_EQ(engine_->stats().chunks_rasterized, before.size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(versions_, std::set<uint64_t>({41, 42}));
  }
  testmap::removeDirectory(other);
}

TEST(ChunkEngine, CreateFailsWithReasons) {
  ChunkEngine::Callbacks cb;
  cb.on_chunk = [](const MapChunkConstPtr& c, uint64_t) { return c; };
  auto missing = ChunkEngine::create("/nonexistent/gmm_map", {}, cb, 1);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("/nonexistent/gmm_map"), std::string::npos);
  ChunkEngineOptions bad;
  bad.raster.num_layers = 9;  // blocks larger than a 128-cell chunk
  EXPECT_FALSE(ChunkEngine::create("/nonexistent", bad, cb, 1).ok());
  bad = ChunkEngineOptions();
  bad.worker_threads = 0;
  auto zero = ChunkEngine::create("/nonexistent", bad, cb, 1);
  ASSERT_FALSE(zero.ok());
  EXPECT_NE(zero.error().find("worker_threads"), std::string::npos);
  EXPECT_FALSE(ChunkEngine::create("/nonexistent", {}, ChunkEngine::Callbacks(), 1).ok());
}

}  // namespace
}  // namespace gmm_localization
