#pragma once
// Private to the map builder: the state shared by pass 1 (map_builder.cpp) and pass 2
// (map_builder_finish.cpp).

#include <memory>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

#include "gmm_localization/core/mapping/map_builder.h"
#include "map_builder_spill.h"

namespace gmm_localization {

struct MapBuilder::Impl {
  MapBuilderOptions options;
  MapBuildStats stats;
  std::string spill_directory;
  std::unique_ptr<map_builder::SpillStore> spill;
  std::set<TileId> own_tiles;              // tiles holding at least one kept point (not only halo)
  std::unordered_set<uint64_t> voxels;     // per-batch voxel filter scratch
  std::vector<std::string> written_files;  // tile files of this build (removed on failure)
  std::string failure;                     // set once a step failed: the builder is then unusable
  bool finished = false;

  // Pass 1 cache: the last tile a point went to.
  TileId last_tile{INT32_MIN, INT32_MIN};
  std::vector<map_builder::SpillRecord>* last_buffer = nullptr;

  Status binPoint(double x, double y, double z);
  void removeSpillDirectory();
};

}  // namespace gmm_localization
