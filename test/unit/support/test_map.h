#pragma once
// A small Gaussian mixture map written to disk by MapBuilder, for the map server's tests (the
// gtests of test/ros and the rostest node of test/integration). Fixed seed, fast (< 1 s).
//
// World: ground z = 0.02 x over x in [-5, 27) m, y in [-3, 13) m; a 3 m wall along x = 12 m for
// y in [2, 8) m; a 2.5 m canopy over the ground at x in [18, 22) m, y in [0, 4) m (two components
// per cell there). Geometry: 0.2 m cells, 32-cell (6.4 m) tiles, origin (-5, -3), so tiles
// (0..4, 0..2) hold data; a raster chunk of 2^5 cells is one tile, offset by nothing.

#include <unistd.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/mapping/map_builder.h"
#include "gmm_localization/core/raster/raster_options.h"

namespace gmm_localization {
namespace testmap {

inline MapGeometry geometry() {
  MapGeometry g;
  g.resolution_m = 0.2;
  g.tile_size_cells = 32;
  g.origin_x_m = -5.0;
  g.origin_y_m = -3.0;
  return g;
}

/// Small chunks and few layers, so a test rasterizes many chunks quickly.
inline RasterOptions rasterOptions() {
  RasterOptions o;
  o.chunk_shift = 5;
  o.num_layers = 3;
  o.z_step_m = 0.1;
  o.z_coarsening_period = 2;
  return o;
}

/// A fresh directory under /tmp (not created).
inline std::string tempDirectory(const std::string& tag) {
  static int counter = 0;
  return "/tmp/gmm_ms_test_" + tag + "_" + std::to_string(::getpid()) + "_" +
         std::to_string(counter++);
}

/// Builds the test map in `directory`.
inline Status build(const std::string& directory) {
  MapBuilderOptions o;
  o.output_directory = directory;
  o.overwrite = true;
  o.geometry = geometry();
  o.threads = 1;
  o.spill_buffer_bytes = size_t{4} << 20;
  auto builder = MapBuilder::create(o);
  if (!builder) return Status::failure(builder.error());
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.f, 0.02f);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  PointBatch batch;
  auto flush = [&]() -> Status {
    Status s = (*builder)->addBatch(batch);
    batch.clear();
    return s;
  };
  for (float x = -5.f; x < 27.f; x += 0.1f) {
    for (float y = -3.f; y < 13.f; y += 0.1f) {
      const float px = x + 0.1f * u(rng), py = y + 0.1f * u(rng);
      batch.points_m.emplace_back(px, py, 0.02f * px + noise(rng));
      if (px >= 18.f && px < 22.f && py >= 0.f && py < 4.f) {
        batch.points_m.emplace_back(px, py, 2.5f + noise(rng));
      }
    }
    if (batch.points_m.size() > 20000) {
      if (Status s = flush(); !s) return s;
    }
  }
  for (float y = 2.f; y < 8.f; y += 0.05f) {
    for (float z = 0.f; z < 3.f; z += 0.05f) {
      batch.points_m.emplace_back(12.f + noise(rng), y, z);
    }
  }
  if (Status s = flush(); !s) return s;
  auto stats = (*builder)->finish();
  if (!stats) return Status::failure(stats.error());
  return Status::success();
}

/// Flips one byte in the middle of a file (a CRC error for a tile).
inline bool corruptFile(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r+b");
  if (f == nullptr) return false;
  std::fseek(f, 0, SEEK_END);
  const long size = std::ftell(f);
  std::fseek(f, size / 2, SEEK_SET);
  const int c = std::fgetc(f);
  std::fseek(f, size / 2, SEEK_SET);
  std::fputc(c ^ 0x5a, f);
  std::fclose(f);
  return true;
}

/// rm -rf of a test directory (only ours, under /tmp/gmm_ms_test_).
inline void removeDirectory(const std::string& directory) {
  if (directory.rfind("/tmp/gmm_ms_test_", 0) != 0) return;
  const std::string cmd = "rm -rf '" + directory + "'";
  if (std::system(cmd.c_str()) != 0) std::perror("rm");
}

}  // namespace testmap
}  // namespace gmm_localization
