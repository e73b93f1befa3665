#pragma once
// Private to the map builder: the state shared by pass 1 (map_builder.cpp) and pass 2
// (map_builder_finish.cpp). The public methods of MapBuilder call the ones here and turn any
// exception into a failure (nothing is thrown across the builder's API).

#include <exception>
#include <memory>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

#include "gmm_localization/core/mapping/map_builder.h"
#include "map_builder_spill.h"
#include "map_builder_staging.h"

namespace gmm_localization {

struct MapBuilder::Impl {
  ~Impl() { abandon(); }  // also on create()'s failures

  MapBuilderOptions options;
  MapBuildStats stats;
  map_builder::DirectoryLock lock;  // on options.output_directory, until finish() or destruction
  std::string staging_directory;    // <output>/.gmm_build.<pid>.<n>: the new tiles, the journal
  std::string spill_directory;      // in staging_directory, or under options.temp_directory
  std::unique_ptr<map_builder::SpillStore> spill;
  std::set<TileId> own_tiles;           // tiles holding at least one kept point (not only halo)
  std::unordered_set<uint64_t> voxels;  // per-batch voxel filter scratch
  std::string failure;                  // set once a step failed: the builder is then unusable
  bool finished = false;

  // Pass 1 cache: the last tile a point went to.
  TileId last_tile{INT32_MIN, INT32_MIN};
  std::vector<map_builder::SpillRecord>* last_buffer = nullptr;

  static Result<std::unique_ptr<MapBuilder>> create(const MapBuilderOptions& options);
  Status addBatch(const PointBatch& batch);
  Result<MapBuildStats> finish(const BuildProgressCallback& progress);

  Status binPoint(double x, double y, double z);
  void removeSpillDirectory();
  /// Removes the spill and staging directories and releases the lock (the output directory is
  /// then as it was before create(), apart from recovered leftovers).
  void abandon();
  /// `error`, with an explanation prepended when it is a full disk or when the staging
  /// directory has disappeared (removed by someone else during the build).
  std::string explain(const std::string& error) const;
  /// Marks the builder failed with explain(error), then abandon()s; returns the reason.
  std::string failWith(const std::string& error);
};

/// What an exception in flight says, for a failure reason. Call from a catch block only.
inline std::string currentExceptionText() {
  try {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "an exception of unknown type";
  }
}

}  // namespace gmm_localization
