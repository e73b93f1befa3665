// Map builder, pass 2: fit and write the tiles into the staging directory on worker threads,
// then swap the new map into the output directory (map_builder_staging.h).
//
// Threads: the workers are owned by a WorkerPool, which stops and joins them in its destructor,
// so they are joined on every path out of finish(): a tile that fails, a cancel, a progress
// callback that throws, a thread that cannot be started, or any other exception. A worker never
// lets an exception out of its thread function (that would std::terminate): it catches it and
// hands it to the caller's thread as that tile's error, which fails the build with a reason.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "map_builder_cells.h"
#include "map_builder_impl.h"

namespace gmm_localization {
namespace {

struct TileOutcome {
  TileInfo info;
  bool written = false;  // false: the tile had no component (no file)
  uint64_t work = 0;
  std::string error;
};

std::string tileName(const TileId& t) {
  return "(" + std::to_string(t.x) + ", " + std::to_string(t.y) + ")";
}

/// Worker threads that are stopped (the flag) and joined when the pool goes out of scope, on
/// every path: a vector of joinable std::thread destroyed during unwinding would std::terminate.
/// Declare it after everything its threads use, so that they are joined before it goes.
class WorkerPool {
 public:
  explicit WorkerPool(std::atomic<bool>& stop) : stop_(stop) {}
  ~WorkerPool() { joinAll(); }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Starts up to `count` threads running `body`. Returns how many started; `error` tells why
  /// the others did not (std::thread throws std::system_error when the system refuses).
  template <typename Body>
  int start(int count, const Body& body, std::string* error) {
    try {
      threads_.reserve(static_cast<size_t>(count));
      while (static_cast<int>(threads_.size()) < count) threads_.emplace_back(body);
    } catch (...) {
      *error = currentExceptionText();
    }
    return static_cast<int>(threads_.size());
  }

  /// Tells the workers to stop after their current tile and waits for them.
  void joinAll() noexcept {
    stop_.store(true);
    for (std::thread& t : threads_) {
      if (t.joinable()) t.join();
    }
    threads_.clear();
  }

 private:
  std::atomic<bool>& stop_;
  std::vector<std::thread> threads_;
};

}  // namespace

Result<MapBuildStats> MapBuilder::Impl::finish(const BuildProgressCallback& progress) {
  using R = Result<MapBuildStats>;
  if (!failure.empty()) return R::failure("map builder unusable: " + failure);
  if (finished) return R::failure("map builder: finish called twice");
  finished = true;
  const MapBuilderOptions& o = options;
  MapBuildStats& st = stats;
  // Every failure below leaves the output directory as it was (see abandon()).
  auto fail = [&](const std::string& why) { return R::failure(failWith(why)); };
  if (st.kept_points == 0) {
    return fail("no points kept: " + std::to_string(st.input_points) + " input, " +
                std::to_string(st.dropped_invalid) + " invalid, " +
                std::to_string(st.dropped_range) + " out of range, " +
                std::to_string(st.dropped_height) + " outside the height band, " +
                (o.layer == MapLayer::kReflectivity
                     ? std::to_string(st.dropped_not_ground) + " not ground returns, "
                     : std::string()) +
                std::to_string(st.dropped_voxel) + " removed by the voxel filter");
  }
  Status flushed = spill->flushAll();
  if (!flushed) return fail(flushed.error());
  st.spill_bytes = spill->bytesWritten();

  const std::vector<TileId> tiles(own_tiles.begin(), own_tiles.end());
  BuildProgress report;
  report.tiles_total = tiles.size();
  for (const TileId& t : tiles) report.work_total += spill->fileBytes(t);

  // Shared with the workers; the pool below is declared after these, so it joins the workers
  // before any of them is destroyed.
  std::mutex mutex;
  std::condition_variable ready;
  std::deque<TileOutcome> outcomes;  // guarded by mutex
  int live_workers = 0;              // guarded by mutex
  std::atomic<size_t> next{0};
  std::atomic<bool> abort{false};
  EmFitterCounters em_total;  // guarded by mutex
  const map_builder::SpillStore& store = *spill;
  const std::string& staging = staging_directory;
  auto worker = [&]() noexcept {
    // Every tile taken from `next` yields exactly one outcome, and a worker that fails in any
    // other way (an exception) delivers an error outcome before it stops.
    std::string in_hand;  // the tile being processed, for the reason of an exception
    try {
      map_builder::TileFitter fitter(o);
      for (;;) {
        const size_t i = next.fetch_add(1);
        if (i >= tiles.size() || abort.load()) break;
        in_hand = tileName(tiles[i]);
        TileOutcome out;
        out.work = store.fileBytes(tiles[i]);
        auto records = store.read(tiles[i]);
        if (!records) {
          out.error = records.error();
        } else {
          auto tile = fitter.fit(tiles[i], *records);
          records->clear();
          records->shrink_to_fit();
          const auto histogram = tile->componentHistogram();
          if (histogram[0] < tile->cells().size()) {
            auto encoded = encodeTile(*tile, o.codec);
            if (!encoded) {
              out.error = encoded.error();
            } else {
              out.info = encoded->info;
              Status w = writeFileAtomic(staging + "/" + out.info.file_name, encoded->bytes);
              if (!w) out.error = w.error();
              out.written = w.ok();
            }
          }
        }
        store.remove(tiles[i]);
        {
          std::lock_guard<std::mutex> lock(mutex);
          outcomes.push_back(std::move(out));
        }
        in_hand.clear();
        ready.notify_one();
      }
      std::lock_guard<std::mutex> lock(mutex);
      em_total.fits += fitter.emCounters().fits;
      em_total.em_runs += fitter.emCounters().em_runs;
      em_total.iterations += fitter.emCounters().iterations;
      em_total.samples += fitter.emCounters().samples;
      --live_workers;
    } catch (...) {
      // Building the reason may fail too (no memory): a fixed one then. Should even the
      // outcome not be queued, the caller sees no worker left and fails the build all the same.
      TileOutcome failed;
      try {
        failed.error = "map build worker thread failed" +
                       (in_hand.empty() ? std::string() : " on tile " + in_hand) + ": " +
                       currentExceptionText();
      } catch (...) {
        failed.error.clear();
      }
      std::lock_guard<std::mutex> lock(mutex);
      try {
        if (failed.error.empty()) failed.error = "map build worker thread failed";
        outcomes.push_back(std::move(failed));
      } catch (...) {
      }
      --live_workers;
    }
    ready.notify_one();
  };

  std::string error;
  MapManifest manifest;
  manifest.geometry = o.geometry;
  manifest.georeference = o.georeference;
  manifest.layer = o.layer;
  if (o.layer == MapLayer::kReflectivity) manifest.reflectivity = o.reflectivity;
  manifest.provenance = o.provenance.empty() ? o.describe() : o.provenance + "; " + o.describe();
  {
    WorkerPool pool(abort);
    const int wanted = std::max(1, std::min<int>(o.threads, static_cast<int>(tiles.size())));
    std::string start_error;
    {
      // Counted before they run, so a worker that ends at once cannot make it negative.
      std::lock_guard<std::mutex> lock(mutex);
      live_workers = wanted;
    }
    const int started = pool.start(wanted, worker, &start_error);
    {
      std::lock_guard<std::mutex> lock(mutex);
      live_workers -= wanted - started;
    }
    // Fewer workers than asked only make the build slower (the output does not depend on it).
    if (started == 0) error = "cannot start a map build worker thread: " + start_error;
    for (size_t received = 0; received < tiles.size() && error.empty();) {
      std::unique_lock<std::mutex> lock(mutex);
      ready.wait(lock, [&] { return !outcomes.empty() || live_workers == 0; });
      if (outcomes.empty()) {  // cannot happen: each worker delivers or reports its failure
        error = "map build worker threads stopped after " + std::to_string(received) + " of " +
                std::to_string(tiles.size()) + " tiles";
        break;
      }
      TileOutcome out = std::move(outcomes.front());
      outcomes.pop_front();
      lock.unlock();
      ++received;
      if (out.written) manifest.tiles.push_back(out.info);
      if (!out.error.empty()) {
        error = out.error;
        break;
      }
      ++report.tiles_done;
      report.work_done += out.work;
      if (!progress) continue;
      try {
        if (!progress(report)) error = "map build cancelled";
      } catch (...) {
        error = "map build stopped: the progress callback threw: " + currentExceptionText();
      }
    }
    pool.joinAll();  // also on every other way out of this block (WorkerPool's destructor)
  }
  removeSpillDirectory();
  if (!error.empty()) return fail(error);
  if (manifest.tiles.empty())
    return fail("no cell received a component (min_own_points too high?)");

  std::sort(manifest.tiles.begin(), manifest.tiles.end(),
            [](const TileInfo& a, const TileInfo& b) { return a.id < b.id; });
  auto manifest_bytes =
      map_builder::commitStagedMap(o.output_directory, staging_directory, manifest, o.overwrite);
  if (!manifest_bytes) return fail(manifest_bytes.error());
  abandon();  // the staging directory, now empty but for the journal; and the lock
  st.tiles = manifest.tiles.size();
  st.em = em_total;
  st.map_bytes = *manifest_bytes;
  for (const TileInfo& t : manifest.tiles) {
    st.map_bytes += t.byte_size;
    for (int k = 0; k <= kMaxMixtureComponents; ++k)
      st.cells_by_components[k] += t.cells_by_components[k];
  }
  report.stage = BuildProgress::Stage::kDone;
  if (progress) {
    // The new map is in place: a callback that throws now cannot undo that, nor fail it.
    try {
      progress(report);
    } catch (...) {
    }
  }
  return st;
}

Result<MapBuildStats> MapBuilder::finish(const BuildProgressCallback& progress) {
  try {
    return impl_->finish(progress);
  } catch (...) {
    // Impl::finish has joined its workers (WorkerPool) by now. Whatever was not done is not
    // committed: the output directory is as it was.
    return Result<MapBuildStats>::failure(
        impl_->failWith("map build failed: unexpected exception: " + currentExceptionText()));
  }
}

}  // namespace gmm_localization
