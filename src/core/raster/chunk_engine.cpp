#include "gmm_localization/core/raster/chunk_engine.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace {

using Clock = std::chrono::steady_clock;

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string inRange(const std::string& key, double v, double lo, double hi) {
  if (v >= lo && v <= hi) return {};
  return key + "=" + std::to_string(v) + " must be in [" + std::to_string(lo) + ", " +
         std::to_string(hi) + "]";
}

/// Opens a map directory and checks it can be served.
Result<std::shared_ptr<const MapStore>> openMap(const std::string& directory) {
  using R = Result<std::shared_ptr<const MapStore>>;
  if (directory.empty()) return R::failure("no map directory given");
  auto store = MapStore::open(directory);
  if (!store) return R::failure(store.error());
  const std::string bad = store->geometry().validate();
  if (!bad.empty()) return R::failure("map '" + directory + "' has an invalid geometry: " + bad);
  if (store->tileIds().empty()) return R::failure("map '" + directory + "' holds no tile");
  return std::shared_ptr<const MapStore>(std::make_shared<MapStore>(std::move(*store)));
}

}  // namespace

std::string ChunkEngineOptions::validate() const {
  for (const std::string& e :
       {inRange("raster_radius_m", raster_radius_m, 0.0, 10000.0),
        inRange("tile_cache_radius_m", tile_cache_radius_m, 0.0, 10000.0),
        inRange("hysteresis_m", hysteresis_m, 0.0, 10000.0),
        inRange("worker_threads", worker_threads, 1, 16),
        inRange("tile_retry_period_s", tile_retry_period_s, 0.01, 86400.0)}) {
    if (!e.empty()) return e;
  }
  return raster.validate();
}

struct ChunkEngine::Job {
  ChunkId id;
  uint64_t version = 0;
  std::shared_ptr<const MapStore> store;
  std::vector<TileId> reads;           // every tile the chunk reads
  std::vector<GmmTileConstPtr> tiles;  // already cached
  std::vector<TileId> to_load;
  bool refresh = false;             // the chunk is held, degraded: a bad tile is due again
  std::set<TileId> missing_before;  // for a refresh: the tiles the held chunk lacks
};

Result<std::unique_ptr<ChunkEngine>> ChunkEngine::create(const std::string& map_directory,
                                                         const ChunkEngineOptions& options,
                                                         Callbacks callbacks,
                                                         uint64_t map_version) {
  using R = Result<std::unique_ptr<ChunkEngine>>;
  const std::string bad = options.validate();
  if (!bad.empty()) return R::failure(bad);
  if (!callbacks.on_chunk) return R::failure("ChunkEngine needs an on_chunk callback");
  auto store = openMap(map_directory);
  if (!store) return R::failure(store.error());
  std::unique_ptr<ChunkEngine> engine(new ChunkEngine(options, std::move(callbacks)));
  {
    std::lock_guard<std::mutex> lock(engine->mutex_);
    engine->installMap(*store, map_version);
  }
  for (int i = 0; i < options.worker_threads; ++i) {
    engine->workers_.emplace_back([e = engine.get()]() { e->workerLoop(); });
  }
  return engine;
}

ChunkEngine::ChunkEngine(const ChunkEngineOptions& options, Callbacks callbacks)
    : options_(options), callbacks_(std::move(callbacks)) {}

ChunkEngine::~ChunkEngine() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ChunkEngine::installMap(std::shared_ptr<const MapStore> store, uint64_t version) {
  planner_ = std::make_unique<ChunkPlanner>(store->geometry(), options_.raster, store->tileIds());
  summary_ = store->summary();
  store_ = std::move(store);
  version_ = version;
  held_.clear();
  tiles_.clear();
  bad_tiles_.clear();
  degraded_.clear();
  pending_ = 0;
  rasterized_ = 0;
  last_raster_ms_ = sum_raster_ms_ = max_raster_ms_ = last_tile_load_ms_ = 0.0;
  dirty_ = true;
}

void ChunkEngine::setCentres(const std::vector<PlanCentre>& centres) {
  if (centres.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (centres == centres_) return;
    centres_ = centres;
    dirty_ = true;
  }
  wake_.notify_all();
}

Status ChunkEngine::switchMap(const std::string& map_directory) {
  auto store = openMap(map_directory);
  if (!store) return Status::failure(store.error());
  {
    std::lock_guard<std::mutex> publish(publish_mutex_);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      installMap(*store, version_ + 1);
    }
    if (callbacks_.on_held_changed) callbacks_.on_held_changed();
  }
  wake_.notify_all();
  idle_.notify_all();
  return Status::success();
}

void ChunkEngine::workerLoop() {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      while (!stop_ && !dirty_) {
        // Asleep until there is work, or until a bad tile that a held chunk lacks is due.
        const Clock::time_point retry = nextRetryLocked();
        if (retry == Clock::time_point::max()) {
          wake_.wait(lock);
        } else if (wake_.wait_until(lock, retry) == std::cv_status::timeout) {
          dirty_ = dirty_ || Clock::now() >= retry;
        }
      }
      if (stop_) return;
    }
    Job job;
    std::vector<ChunkId> evicted;
    bool have_job = false;
    {
      std::lock_guard<std::mutex> publish(publish_mutex_);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stop_) return;
        have_job = plan(job, evicted);
      }
      if (!evicted.empty() && callbacks_.on_held_changed) callbacks_.on_held_changed();
    }
    idle_.notify_all();
    if (have_job) runJob(job);
  }
}

bool ChunkEngine::plan(Job& job, std::vector<ChunkId>& evicted) {
  if (!planner_ || centres_.empty()) {
    dirty_ = false;
    pending_ = 0;
    return false;
  }
  // Evict what the vehicle has left behind (with hysteresis, so a vehicle driving along a
  // chunk border does not make chunks come and go).
  std::vector<ChunkId> held_ids;
  for (const auto& kv : held_) held_ids.push_back(kv.first);
  evicted = planner_->toEvict(held_ids, centres_, options_.raster_radius_m + options_.hysteresis_m);
  for (const ChunkId& id : evicted) {
    held_.erase(id);
    degraded_.erase(id);
  }
  const double tile_keep = options_.tile_cache_radius_m + options_.hysteresis_m;
  for (auto it = tiles_.begin(); it != tiles_.end();) {
    it = planner_->distanceToTile(it->first, centres_) > tile_keep ? tiles_.erase(it) : ++it;
  }

  const std::vector<ChunkId> needed = planner_->needed(centres_, options_.raster_radius_m);
  pending_ = 0;
  const ChunkId* next = nullptr;
  for (const ChunkId& id : needed) {
    if (held_.count(id) > 0) continue;
    ++pending_;
    if (next == nullptr && in_progress_.count(id) == 0) next = &id;
  }
  const Clock::time_point now = Clock::now();
  if (next == nullptr) {
    // Nothing new is needed: time to retry a bad tile for a chunk served without it?
    next = dueRefreshLocked(now);
    if (next == nullptr) {
      dirty_ = false;
      return false;
    }
    job.refresh = true;
    job.missing_before = degraded_.at(*next);
  }
  job.id = *next;
  job.version = version_;
  job.store = store_;
  collectTilesLocked(job, now);
  in_progress_.insert(job.id);
  return true;
}

const ChunkId* ChunkEngine::dueRefreshLocked(Clock::time_point now) const {
  for (const auto& [id, missing] : degraded_) {
    if (in_progress_.count(id) > 0) continue;
    for (const TileId& t : missing) {
      auto bad = bad_tiles_.find(t);
      // Due, or no longer bad (another chunk's job loaded it meanwhile).
      if (bad == bad_tiles_.end() || bad->second.retry_at <= now) return &id;
    }
  }
  return nullptr;
}

void ChunkEngine::collectTilesLocked(Job& job, Clock::time_point now) {
  job.reads = planner_->tilesFor(job.id);
  for (const TileId& t : job.reads) {
    auto cached = tiles_.find(t);
    if (cached != tiles_.end()) {
      job.tiles.push_back(cached->second);
      continue;
    }
    auto bad = bad_tiles_.find(t);
    if (bad != bad_tiles_.end()) {
      if (bad->second.retry_at > now) continue;  // served as empty until its next retry
      bad->second.retry_at = now + seconds(options_.tile_retry_period_s);  // one try per period
    }
    job.to_load.push_back(t);
  }
}

ChunkEngine::Clock::time_point ChunkEngine::nextRetryLocked() const {
  Clock::time_point next = Clock::time_point::max();
  for (const auto& [id, missing] : degraded_) {
    if (in_progress_.count(id) > 0) continue;  // its job's end wakes the workers anyway
    for (const TileId& t : missing) {
      auto bad = bad_tiles_.find(t);
      next = std::min(next, bad == bad_tiles_.end() ? Clock::time_point() : bad->second.retry_at);
    }
  }
  return next;
}

void ChunkEngine::runJob(Job& job) {
  for (const TileId& t : job.to_load) {
    const auto t0 = Clock::now();
    auto tile = job.store->loadTile(t);
    const double load_ms = msSince(t0);
    bool report = false, recovered = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (job.version == version_) {
        if (tile) {
          tiles_.emplace(t, *tile);
          last_tile_load_ms_ = load_ms;
          recovered = bad_tiles_.erase(t) > 0;
        } else {
          auto bad = bad_tiles_.find(t);
          report = bad == bad_tiles_.end();
          if (report) {
            bad = bad_tiles_.emplace(t, BadTile{}).first;
            bad->second.retry_at = Clock::now() + seconds(options_.tile_retry_period_s);
          }
          bad->second.reason = tile.error();
        }
      }
    }
    if (tile) {
      job.tiles.push_back(*tile);
      if (recovered && callbacks_.on_tile_recovered) callbacks_.on_tile_recovered(t);
    } else if (report && callbacks_.on_tile_error) {
      callbacks_.on_tile_error(t, tile.error());
    }
  }
  // The tiles the chunk reads but goes without (bad now, or bad and not yet due).
  std::set<TileId> missing(job.reads.begin(), job.reads.end());
  for (const GmmTileConstPtr& t : job.tiles) missing.erase(t->id());
  if (job.refresh && missing == job.missing_before) {
    // Still the same tiles missing: the held chunk stays as it is, nothing is republished.
    {
      std::lock_guard<std::mutex> lock(mutex_);
      in_progress_.erase(job.id);
      dirty_ = true;
    }
    wake_.notify_all();
    idle_.notify_all();
    return;
  }

  // A bad tile is simply absent: its cells read as empty (the floor), the rest is served.
  GmmMap map(job.store->geometry());
  for (const GmmTileConstPtr& t : job.tiles) map.insert(t);
  const auto t0 = Clock::now();
  auto chunk = rasterizeChunk(map, job.id, options_.raster);
  const double raster_ms = msSince(t0);
  map = GmmMap();
  job.tiles.clear();

  {
    std::lock_guard<std::mutex> publish(publish_mutex_);
    bool keep = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      in_progress_.erase(job.id);
      dirty_ = true;
      keep = chunk.ok() && !stop_ && job.version == version_ &&
             planner_->distanceToChunk(job.id, centres_) <=
                 options_.raster_radius_m + options_.hysteresis_m;
      // A refresh that cannot replace the held chunk is not tried again and again.
      if (job.refresh && !keep && job.version == version_) degraded_.erase(job.id);
      if (chunk.ok() && job.version == version_) {
        ++rasterized_;
        last_raster_ms_ = raster_ms;
        sum_raster_ms_ += raster_ms;
        max_raster_ms_ = std::max(max_raster_ms_, raster_ms);
      }
    }
    if (keep) {
      MapChunkConstPtr to_hold = callbacks_.on_chunk(*chunk, job.version);
      if (to_hold) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          held_[job.id] = std::move(to_hold);
          if (missing.empty()) {
            degraded_.erase(job.id);
          } else {
            degraded_[job.id] = missing;
          }
        }
        if (callbacks_.on_held_changed) callbacks_.on_held_changed();
      }
    }
  }
  wake_.notify_all();
  idle_.notify_all();
}

bool ChunkEngine::idleLocked() const { return !dirty_ && in_progress_.empty() && pending_ == 0; }

bool ChunkEngine::waitIdle(double timeout_s) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return idle_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                        [this]() { return idleLocked(); });
}

std::vector<MapChunkConstPtr> ChunkEngine::held() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<MapChunkConstPtr> out;
  out.reserve(held_.size());
  for (const auto& kv : held_) out.push_back(kv.second);
  return out;
}

uint64_t ChunkEngine::mapVersion() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

std::shared_ptr<const MapStore> ChunkEngine::store() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return store_;
}

MapSummary ChunkEngine::mapSummary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return summary_;
}

ChunkEngineStats ChunkEngine::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  ChunkEngineStats s;
  s.map_version = version_;
  s.map_directory = store_ ? store_->directory() : std::string();
  s.tiles_in_map = summary_.tiles;
  s.tiles_cached = tiles_.size();
  s.chunks_held = held_.size();
  s.chunks_pending = pending_;
  s.chunks_in_progress = in_progress_.size();
  for (const auto& kv : held_) s.raster_bytes += kv.second->bytes();
  s.chunks_rasterized = rasterized_;
  s.last_raster_ms = last_raster_ms_;
  s.mean_raster_ms = rasterized_ > 0 ? sum_raster_ms_ / static_cast<double>(rasterized_) : 0.0;
  s.max_raster_ms = max_raster_ms_;
  s.last_tile_load_ms = last_tile_load_ms_;
  for (const auto& [tile, bad] : bad_tiles_) s.tile_errors[tile] = bad.reason;
  s.chunks_degraded = degraded_.size();
  s.has_centres = !centres_.empty();
  return s;
}

}  // namespace gmm_localization
