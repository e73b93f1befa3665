// The map server's engine retries tiles that failed to load: once the directory is restored,
// the chunks served without the tile are rasterized again (same map version) and equal the
// full map; while the tile stays broken nothing is republished and it is reported once.
#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/core/raster/chunk_engine.h"
#include "gmm_localization/core/raster/rasterizer.h"
#include "support/test_map.h"

namespace gmm_localization {
namespace {

constexpr double kRetryS = 0.05;
const TileId kBad{3, 1};  // a chunk of its own and the reach of chunk (2, 1)
const PlanCentre kAt(10.0, 5.0);

class EngineRetryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testmap::tempDirectory("engine_retry");
    const Status s = testmap::build(dir_);
    ASSERT_TRUE(s.ok()) << s.error();
    auto store = MapStore::open(dir_);
    ASSERT_TRUE(store.ok());
    const TileInfo* info = store->tileInfo(kBad);
    ASSERT_NE(info, nullptr);
    path_ = dir_ + "/" + info->file_name;
    auto bytes = readFileBytes(path_);
    ASSERT_TRUE(bytes.ok());
    original_ = *bytes;
    auto all = store->loadAll();
    ASSERT_TRUE(all.ok());
    full_ = std::move(*all);
    options_.raster = testmap::rasterOptions();
    options_.raster_radius_m = 8.0;
    options_.tile_cache_radius_m = 8.0;
    options_.hysteresis_m = 4.0;
    options_.tile_retry_period_s = kRetryS;
    options_.worker_threads = 2;
  }
  void TearDown() override {
    engine_.reset();
    testmap::removeDirectory(dir_);
  }

  void start() {
    ChunkEngine::Callbacks cb;
    cb.on_chunk = [this](const MapChunkConstPtr& c, uint64_t) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++published_;
      return c;
    };
    cb.on_tile_error = [this](const TileId&, const std::string&) { ++errors_; };
    cb.on_tile_recovered = [this](const TileId& t) {
      EXPECT_EQ(t, kBad);
      ++recovered_;
    };
    auto e = ChunkEngine::create(dir_, options_, cb, 7);
    ASSERT_TRUE(e.ok()) << e.error();
    engine_ = std::move(*e);
  }

  bool heldEqualToFullMap() {
    for (const MapChunkConstPtr& got : engine_->held()) {
      auto want = rasterizeChunk(full_, got->id(), options_.raster);
      if (!want.ok() || !got->sameTables(**want) || got->mixtures() != (*want)->mixtures()) {
        return false;
      }
    }
    return true;
  }

  /// Polls `done` for up to timeout_s.
  template <typename F>
  bool waitUntil(F done, double timeout_s) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return done();
  }

  size_t published() {
    std::lock_guard<std::mutex> lock(mutex_);
    return published_;
  }

  std::string dir_, path_;
  std::vector<uint8_t> original_;
  GmmMap full_;
  ChunkEngineOptions options_;
  std::unique_ptr<ChunkEngine> engine_;
  std::mutex mutex_;
  size_t published_ = 0;
  std::atomic<int> errors_{0}, recovered_{0};
};

TEST_F(EngineRetryTest, RestoredTileIsServedAgainWithoutAReload) {
  ASSERT_TRUE(testmap::corruptFile(path_));
  start();
  engine_->setCentres({kAt});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  ChunkEngineStats st = engine_->stats();
  ASSERT_EQ(st.tile_errors.count(kBad), 1u);
  EXPECT_NE(st.tile_errors.at(kBad).find("CRC"), std::string::npos) << st.tile_errors.at(kBad);
  EXPECT_GT(st.chunks_degraded, 0u);
  EXPECT_FALSE(heldEqualToFullMap()) << "served without the tile";
  const size_t held = st.chunks_held;

  // Still broken over several retry periods: retried, but reported once and not republished.
  const size_t before = published();
  std::this_thread::sleep_for(std::chrono::duration<double>(10 * kRetryS));
  EXPECT_EQ(errors_.load(), 1);
  EXPECT_EQ(published(), before);
  EXPECT_EQ(engine_->stats().tile_errors.count(kBad), 1u);

  // The directory is restored: the tile loads at its next retry and its chunks are replaced.
  ASSERT_TRUE(writeFileAtomic(path_, original_).ok());
  ASSERT_TRUE(waitUntil(
      [&]() {
        const ChunkEngineStats now = engine_->stats();
        return now.tile_errors.empty() && now.chunks_degraded == 0 && now.chunks_in_progress == 0;
      },
      10.0))
      << "the restored tile was never loaded again";
  EXPECT_EQ(recovered_.load(), 1);
  EXPECT_TRUE(heldEqualToFullMap());
  st = engine_->stats();
  EXPECT_EQ(st.map_version, 7u) << "healed in place, no new map version";
  EXPECT_EQ(st.chunks_held, held);
  EXPECT_GT(published(), before) << "the healed chunks were published again";
  EXPECT_LE(published(), before + st.chunks_held);
}

TEST_F(EngineRetryTest, TruncatedTileIsRetriedToo) {
  std::vector<uint8_t> truncated(original_.begin(), original_.begin() + original_.size() / 3);
  ASSERT_TRUE(writeFileAtomic(path_, truncated).ok());
  start();
  engine_->setCentres({kAt});
  ASSERT_TRUE(engine_->waitIdle(30.0));
  ASSERT_EQ(engine_->stats().tile_errors.count(kBad), 1u);
  EXPECT_NE(engine_->stats().tile_errors.at(kBad).find("truncated"), std::string::npos)
      << engine_->stats().tile_errors.at(kBad);
  ASSERT_TRUE(writeFileAtomic(path_, original_).ok());
  EXPECT_TRUE(waitUntil(
      [&]() {
        const ChunkEngineStats now = engine_->stats();
        return now.tile_errors.empty() && now.chunks_degraded == 0 && now.chunks_in_progress == 0;
      },
      10.0));
  EXPECT_TRUE(heldEqualToFullMap());
}

TEST(ChunkEngineRetry, RetryPeriodIsValidated) {
  ChunkEngineOptions o;
  o.tile_retry_period_s = 0.0;
  EXPECT_NE(o.validate().find("tile_retry_period_s"), std::string::npos);
  o.tile_retry_period_s = 10.0;
  EXPECT_TRUE(o.validate().empty());
}

}  // namespace
}  // namespace gmm_localization
