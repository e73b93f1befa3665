// Map builder, pass 2: fit and write the tiles into the staging directory on worker threads,
// then swap the new map into the output directory (map_builder_staging.h).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
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

}  // namespace

Result<MapBuildStats> MapBuilder::finish(const BuildProgressCallback& progress) {
  using R = Result<MapBuildStats>;
  Impl& m = *impl_;
  if (!m.failure.empty()) return R::failure("map builder unusable: " + m.failure);
  if (m.finished) return R::failure("map builder: finish called twice");
  m.finished = true;
  const MapBuilderOptions& o = m.options;
  MapBuildStats& st = m.stats;
  // Every failure below leaves the output directory as it was (see abandon()).
  auto fail = [&](const std::string& why) {
    m.abandon();
    return R::failure(m.explain(why));
  };
  if (st.kept_points == 0) {
    return fail("no points kept: " + std::to_string(st.input_points) + " input, " +
                std::to_string(st.dropped_invalid) + " invalid, " +
                std::to_string(st.dropped_range) + " out of range, " +
                std::to_string(st.dropped_height) + " outside the height band, " +
                std::to_string(st.dropped_voxel) + " removed by the voxel filter");
  }
  Status flushed = m.spill->flushAll();
  if (!flushed) return fail(flushed.error());
  st.spill_bytes = m.spill->bytesWritten();

  const std::vector<TileId> tiles(m.own_tiles.begin(), m.own_tiles.end());
  BuildProgress report;
  report.tiles_total = tiles.size();
  for (const TileId& t : tiles) report.work_total += m.spill->fileBytes(t);

  std::mutex mutex;
  std::condition_variable ready;
  std::deque<TileOutcome> outcomes;
  std::atomic<size_t> next{0};
  std::atomic<bool> abort{false};
  EmFitterCounters em_total;
  auto worker = [&]() {
    map_builder::TileFitter fitter(o);
    for (;;) {
      const size_t i = next.fetch_add(1);
      if (i >= tiles.size() || abort.load()) {
        std::lock_guard<std::mutex> lock(mutex);
        em_total.fits += fitter.emCounters().fits;
        em_total.em_runs += fitter.emCounters().em_runs;
        em_total.iterations += fitter.emCounters().iterations;
        em_total.samples += fitter.emCounters().samples;
        return;
      }
      TileOutcome out;
      out.work = m.spill->fileBytes(tiles[i]);
      auto records = m.spill->read(tiles[i]);
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
            Status w =
                writeFileAtomic(m.staging_directory + "/" + out.info.file_name, encoded->bytes);
            if (!w) out.error = w.error();
            out.written = w.ok();
          }
        }
      }
      m.spill->remove(tiles[i]);
      {
        std::lock_guard<std::mutex> lock(mutex);
        outcomes.push_back(std::move(out));
      }
      ready.notify_one();
    }
  };
  std::vector<std::thread> pool;
  const int workers = std::max(1, std::min<int>(o.threads, static_cast<int>(tiles.size())));
  for (int w = 0; w < workers; ++w) pool.emplace_back(worker);

  std::string error;
  MapManifest manifest;
  manifest.geometry = o.geometry;
  manifest.georeference = o.georeference;
  manifest.provenance = o.provenance.empty() ? o.describe() : o.provenance + "; " + o.describe();
  for (size_t received = 0; received < tiles.size() && error.empty();) {
    std::unique_lock<std::mutex> lock(mutex);
    ready.wait(lock, [&] { return !outcomes.empty(); });
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
    if (progress && !progress(report)) error = "map build cancelled";
  }
  abort.store(true);
  for (std::thread& t : pool) t.join();
  m.removeSpillDirectory();
  if (!error.empty()) return fail(error);
  if (manifest.tiles.empty())
    return fail("no cell received a component (min_own_points too high?)");

  std::sort(manifest.tiles.begin(), manifest.tiles.end(),
            [](const TileInfo& a, const TileInfo& b) { return a.id < b.id; });
  auto manifest_bytes =
      map_builder::commitStagedMap(o.output_directory, m.staging_directory, manifest, o.overwrite);
  if (!manifest_bytes) return fail(manifest_bytes.error());
  m.abandon();  // the staging directory, now empty but for the journal; and the lock
  st.tiles = manifest.tiles.size();
  st.em = em_total;
  st.map_bytes = *manifest_bytes;
  for (const TileInfo& t : manifest.tiles) {
    st.map_bytes += t.byte_size;
    for (int k = 0; k <= kMaxMixtureComponents; ++k)
      st.cells_by_components[k] += t.cells_by_components[k];
  }
  report.stage = BuildProgress::Stage::kDone;
  if (progress) progress(report);
  return st;
}

}  // namespace gmm_localization
