#include "gmm_localization/core/mapping/map_builder.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <system_error>

#include <gtest/gtest.h>

#include "gmm_localization/core/map/map_store.h"
#include "support/temp_dir.h"

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;

using testing::TempDir;

/// An analytic world: surfaces sampled on a regular lattice with Gaussian height noise, fed to
/// the builder in batches of `batch_size` points (no sensor origin).
class World {
 public:
  void plane(double x0, double x1, double y0, double y1, double z, double step = 0.04) {
    for (double x = x0 + step / 2; x < x1; x += step) {
      for (double y = y0 + step / 2; y < y1; y += step) add(x, y, z);
    }
  }
  /// A vertical wall at x = x_wall spanning y0..y1 and z0..z1.
  void wallX(double x_wall, double y0, double y1, double z0, double z1, double step = 0.04) {
    for (double y = y0 + step / 2; y < y1; y += step) {
      for (double z = z0 + step / 2; z < z1; z += step) add(x_wall, y, z);
    }
  }
  void add(double x, double y, double z) { points_.emplace_back(x, y, z + noise_(rng_)); }
  Status feed(MapBuilder& b, size_t batch_size = 5000) const {
    PointBatch batch;
    for (size_t i = 0; i < points_.size(); i += batch_size) {
      batch.points_m.assign(points_.begin() + i,
                            points_.begin() + std::min(points_.size(), i + batch_size));
      Status s = b.addBatch(batch);
      if (!s) return s;
    }
    return Status::success();
  }
  size_t size() const { return points_.size(); }

 private:
  std::mt19937 rng_{42};
  std::normal_distribution<float> noise_{0.f, 0.01f};
  std::vector<Eigen::Vector3f> points_;
};

/// Every regular file directly in `dir`, name -> bytes (sub-directories are left out).
std::map<std::string, std::vector<uint8_t>> snapshot(const std::string& dir) {
  std::map<std::string, std::vector<uint8_t>> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    auto bytes = readFileBytes(e.path().string());
    EXPECT_TRUE(bytes.ok()) << bytes.error();
    if (bytes) files[e.path().filename()] = *bytes;
  }
  return files;
}

/// Staging directories (".gmm_build.*") in `dir`.
std::vector<std::string> stagingDirectories(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename();
    if (name.rfind(".gmm_build.", 0) == 0) found.push_back(e.path().string());
  }
  return found;
}

/// Removes `path` with all it holds while a build's worker may be creating files in it: a file
/// created between remove_all's listing and its rmdir fails that round (ENOTEMPTY), so it is
/// retried until the directory is gone. Afterwards nothing can be created in it any more, which
/// makes the build's outcome deterministic: it must fail.
void removeWhileInUse(const std::string& path) {
  std::error_code ec;
  for (int round = 0; fs::exists(path, ec) || ec; ++round) {
    ASSERT_LT(round, 10000) << "cannot remove " << path << ": " << ec.message();
    fs::remove_all(path, ec);
  }
}

/// The map in `dir` opens, every tile loads, and it is exactly the files `expected` holds.
void expectIntactMap(const std::string& dir,
                     const std::map<std::string, std::vector<uint8_t>>& expected) {
  EXPECT_TRUE(snapshot(dir) == expected) << "the files in " << dir << " changed";
  auto store = MapStore::open(dir);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_TRUE(store->verify().empty());
  EXPECT_EQ(store->tileIds().size() + 1, expected.size());
}

MapBuilderOptions options(const std::string& dir, int tile_size = 64) {
  MapBuilderOptions o;
  o.output_directory = dir;
  o.geometry.tile_size_cells = tile_size;
  return o;
}

Result<MapStore> build(const World& w, const MapBuilderOptions& o, MapBuildStats* stats = nullptr) {
  auto b = MapBuilder::create(o);
  if (!b) return Result<MapStore>::failure(b.error());
  Status s = w.feed(**b);
  if (!s) return Result<MapStore>::failure(s.error());
  auto st = (*b)->finish();
  if (!st) return Result<MapStore>::failure(st.error());
  if (stats) *stats = *st;
  return MapStore::open(o.output_directory);
}

/// The mixture of the cell containing (x, y), from a loaded map.
GaussianMixture1D cellAt(const GmmMap& map, double x, double y) {
  const GaussianMixture1D* g = map.cell(map.geometry().cellAt(x, y));
  return g ? *g : GaussianMixture1D();
}

TEST(MapBuilder, FlatGroundIsOneTightComponent) {
  TempDir dir("gmm_map_builder");
  World w;
  w.plane(0.0, 10.0, 0.0, 10.0, 0.25);
  auto store = build(w, options(dir.path));
  ASSERT_TRUE(store.ok()) << store.error();
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok()) << map.error();
  for (double x = 0.1; x < 10.0; x += 0.2) {
    for (double y = 0.1; y < 10.0; y += 0.2) {
      const auto g = cellAt(*map, x, y);
      ASSERT_EQ(g.size(), 1) << x << ", " << y;
      EXPECT_NEAR(g.component(0).mean_m, 0.25, 0.005);
      EXPECT_GE(g.component(0).sigma_m, 0.03f - 1e-5f);  // the floor
      EXPECT_LE(g.component(0).sigma_m, 0.036f);         // floor + 1 cm noise + 1 cm bins
    }
  }
  EXPECT_TRUE(cellAt(*map, -0.1, 5.0).empty());  // outside the ground: nothing invented
  EXPECT_TRUE(cellAt(*map, 5.0, 10.1).empty());
}

TEST(MapBuilder, WallIsOneWideComponentSpanningItsHeight) {
  TempDir dir("gmm_map_builder");
  World w;
  w.wallX(5.1, 0.0, 10.0, 0.0, 6.0);
  auto store = build(w, options(dir.path));
  ASSERT_TRUE(store.ok()) << store.error();
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok());
  for (double y = 0.3; y < 9.8; y += 0.2) {
    const auto g = cellAt(*map, 5.1, y);
    ASSERT_EQ(g.size(), 1) << "y=" << y;
    EXPECT_NEAR(g.component(0).mean_m, 3.0, 0.02);
    EXPECT_NEAR(g.component(0).sigma_m, 6.0 / std::sqrt(12.0), 0.03);
    EXPECT_TRUE(cellAt(*map, 4.9, y).empty());  // beside the wall: no own points, empty
    EXPECT_TRUE(cellAt(*map, 5.3, y).empty());
  }
}

TEST(MapBuilder, GroundBesideAWallGetsTightGroundAndWideWall) {
  // The paper's facade cells: ground plus the blurred-in wall.
  TempDir dir("gmm_map_builder");
  World w;
  w.plane(0.0, 5.0, 0.0, 10.0, 0.0);
  w.wallX(5.1, 0.0, 10.0, 0.0, 6.0);
  auto store = build(w, options(dir.path));
  ASSERT_TRUE(store.ok()) << store.error();
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok());
  const auto g = cellAt(*map, 4.9, 5.0);
  ASSERT_EQ(g.size(), 2);
  EXPECT_NEAR(g.component(0).mean_m, 0.0, 0.01);
  EXPECT_LT(g.component(0).sigma_m, 0.04f);
  EXPECT_GT(g.component(1).sigma_m, 1.0f);
  const auto far = cellAt(*map, 2.0, 5.0);
  ASSERT_EQ(far.size(), 1);
  EXPECT_NEAR(far.component(0).mean_m, 0.0, 0.01);
}

TEST(MapBuilder, OverhangOverGroundIsTwoComponentsAtTheRightHeights) {
  TempDir dir("gmm_map_builder");
  World w;
  w.plane(0.0, 10.0, 0.0, 10.0, 0.0);
  w.plane(2.0, 8.0, 2.0, 8.0, 3.0);  // an awning 3 m up
  auto store = build(w, options(dir.path));
  ASSERT_TRUE(store.ok()) << store.error();
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok());
  for (double x = 2.5; x < 7.5; x += 0.2) {
    for (double y = 2.5; y < 7.5; y += 0.2) {
      const auto g = cellAt(*map, x, y);
      ASSERT_EQ(g.size(), 2) << x << ", " << y;
      EXPECT_NEAR(g.component(0).mean_m, 0.0, 0.01);
      EXPECT_NEAR(g.component(1).mean_m, 3.0, 0.01);
      EXPECT_LT(g.component(0).sigma_m, 0.036f);
      EXPECT_LT(g.component(1).sigma_m, 0.036f);
      EXPECT_NEAR(g.component(0).weight, 0.5, 0.05);
    }
  }
  EXPECT_EQ(cellAt(*map, 1.0, 1.0).size(), 1);
}

TEST(MapBuilder, EmptyAreaHasNoComponentsAndNoTiles) {
  TempDir dir("gmm_map_builder");
  World w;
  w.plane(0.0, 4.0, 0.0, 4.0, 0.0);
  w.plane(30.0, 34.0, 0.0, 4.0, 0.0);  // 64-cell tiles are 12.8 m: tiles 0 and 2 only
  auto store = build(w, options(dir.path));
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->tileIds(), (std::vector<TileId>{{0, 0}, {2, 0}}));
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok());
  EXPECT_TRUE(cellAt(*map, 10.0, 2.0).empty());
  EXPECT_TRUE(cellAt(*map, 5.0, 5.0).empty());
  const MapSummary s = store->summary();
  EXPECT_EQ(s.cells_by_components[1], 2u * 20 * 20);
  EXPECT_EQ(s.cells_by_components[2] + s.cells_by_components[3], 0u);
}

/// Builds a mixed world with the given tile size, grid origin and buffer; returns the map.
GmmMap buildMixed(const std::string& dir, int tile_size, double origin_m, size_t buffer_bytes,
                  int threads) {
  World w;
  w.plane(-3.0, 9.0, -3.0, 9.0, 0.0);
  w.plane(1.0, 5.0, -2.0, 4.0, 2.5);
  w.wallX(3.05, -3.0, 9.0, 0.0, 4.0);
  MapBuilderOptions o = options(dir, tile_size);
  o.geometry.origin_x_m = o.geometry.origin_y_m = origin_m;
  o.spill_buffer_bytes = buffer_bytes;
  o.threads = threads;
  auto store = build(w, o);
  EXPECT_TRUE(store.ok()) << store.error();
  auto map = store->loadAll();
  EXPECT_TRUE(map.ok());
  return map.ok() ? *map : GmmMap();
}

TEST(MapBuilder, StreamingOverTileBordersMatchesSingleTileReference) {
  TempDir a("gmm_map_builder"), b("gmm_map_builder");
  // 16-cell tiles (3.2 m) from origin 0: the world (-3..9 m) straddles 4 x 4 tiles, with
  // negative indices, and the blur halo crosses every border. 256-cell tiles from origin
  // -12.8 m (a whole number of cells away, so cells coincide): one tile holds it all.
  const GmmMap tiled = buildMixed(a.path, 16, 0.0, size_t{1} << 20, 2);
  const GmmMap single = buildMixed(b.path, 256, -12.8, size_t{256} << 20, 1);
  EXPECT_EQ(tiled.tiles().size(), 16u);
  EXPECT_EQ(single.tiles().size(), 1u);
  int compared = 0, two = 0;
  for (double x = -3.9; x < 10.0; x += 0.2) {
    for (double y = -3.9; y < 10.0; y += 0.2) {
      const GaussianMixture1D* p = tiled.cell(tiled.geometry().cellAt(x, y));
      const GaussianMixture1D* q = single.cell(single.geometry().cellAt(x, y));
      const int kp = p ? p->size() : 0, kq = q ? q->size() : 0;
      ASSERT_EQ(kp, kq) << "cell at " << x << ", " << y;
      for (int c = 0; c < kp; ++c) {
        // Same fit; only the per-tile mean quantum (<= 0.5 mm) differs.
        EXPECT_NEAR(p->component(c).mean_m, q->component(c).mean_m, 1.1e-3);
        EXPECT_NEAR(p->component(c).sigma_m, q->component(c).sigma_m, 1e-4);
        EXPECT_NEAR(p->component(c).weight, q->component(c).weight, 1e-4);
      }
      compared += kp > 0;
      two += kp == 2;
    }
  }
  EXPECT_EQ(compared, 60 * 60);
  EXPECT_GT(two, 100);
}

TEST(MapBuilder, OutputIsDeterministicAcrossThreadsAndBuffers) {
  TempDir a("gmm_map_builder"), b("gmm_map_builder");
  buildMixed(a.path, 32, 0.0, size_t{1} << 20, 1);
  buildMixed(b.path, 32, 0.0, size_t{64} << 20, 2);
  auto ma = readManifest(a.path), mb = readManifest(b.path);
  ASSERT_TRUE(ma.ok() && mb.ok());
  ASSERT_EQ(ma->tiles.size(), mb->tiles.size());
  for (size_t i = 0; i < ma->tiles.size(); ++i) {
    EXPECT_EQ(ma->tiles[i].id, mb->tiles[i].id);
    EXPECT_EQ(ma->tiles[i].crc32, mb->tiles[i].crc32);  // byte-identical tile files
  }
}

TEST(MapBuilder, FiltersAreAppliedAndCounted) {
  TempDir dir("gmm_map_builder");
  MapBuilderOptions o = options(dir.path);
  o.min_range_m = 2.0;
  o.max_range_m = 10.0;
  o.min_z_m = -1.0;
  o.max_z_m = 5.0;
  auto b = MapBuilder::create(o);
  ASSERT_TRUE(b.ok()) << b.error();
  PointBatch scan;
  scan.has_sensor_origin = true;
  scan.sensor_origin_m = {0.0, 0.0, 2.0};
  scan.points_m = {{3.f, 0.f, 0.f},  {0.5f, 0.f, 2.f},   // kept, too close
                   {20.f, 0.f, 0.f}, {3.f, 1.f, 6.f},    // too far, too high
                   {NAN, 0.f, 0.f},  {3.f, 2.f, -0.5f},  // invalid, kept
                   {1e8f, 0.f, 0.f}};                    // beyond the map frame
  ASSERT_TRUE((*b)->addBatch(scan).ok());
  PointBatch cloud;  // no sensor origin: no range filter
  cloud.points_m = {{50.f, 0.f, 0.f}, {0.1f, 0.f, 2.f}};
  ASSERT_TRUE((*b)->addBatch(cloud).ok());
  const MapBuildStats& s = (*b)->stats();
  EXPECT_EQ(s.batches, 2u);
  EXPECT_EQ(s.batches_without_origin, 1u);
  EXPECT_EQ(s.input_points, 9u);
  EXPECT_EQ(s.kept_points, 4u);
  EXPECT_EQ(s.dropped_range, 2u);
  EXPECT_EQ(s.dropped_height, 1u);
  EXPECT_EQ(s.dropped_invalid, 2u);
  auto st = (*b)->finish();
  ASSERT_TRUE(st.ok()) << st.error();
  EXPECT_EQ(st->cells_by_components[1], 4u);
}

TEST(MapBuilder, VoxelFilterKeepsOnePointPerVoxelPerBatch) {
  TempDir dir("gmm_map_builder");
  MapBuilderOptions o = options(dir.path);
  o.voxel_m = 0.1;
  auto b = MapBuilder::create(o);
  ASSERT_TRUE(b.ok());
  PointBatch batch;
  for (int i = 0; i < 10; ++i) batch.points_m.emplace_back(0.01f * i, 0.05f, 0.05f);  // one voxel
  batch.points_m.emplace_back(0.35f, 0.05f, 0.05f);
  ASSERT_TRUE((*b)->addBatch(batch).ok());
  ASSERT_TRUE((*b)->addBatch(batch).ok());  // the filter is per batch
  EXPECT_EQ((*b)->stats().kept_points, 4u);
  EXPECT_EQ((*b)->stats().dropped_voxel, 18u);
}

TEST(MapBuilder, TemporaryFilesAreRemovedOnSuccessFailureAndCancel) {
  TempDir dir("gmm_map_builder");
  World w;
  w.plane(0.0, 20.0, 0.0, 20.0, 0.0);
  {  // Success: only the manifest and tile files remain.
    auto store = build(w, options(dir.path + "/ok", 32));
    ASSERT_TRUE(store.ok());
    for (const auto& e : fs::directory_iterator(dir.path + "/ok")) {
      const std::string name = e.path().filename();
      EXPECT_TRUE(name == "manifest.gmm" || name.rfind("tile_", 0) == 0) << name;
    }
  }
  {  // Abandoned before finish(): the destructor removes the spill directory.
    auto b = MapBuilder::create(options(dir.path + "/abandoned", 32));
    ASSERT_TRUE(b.ok());
    ASSERT_TRUE(w.feed(**b).ok());
    EXPECT_FALSE(fs::is_empty(dir.path + "/abandoned"));
    b->reset();
    EXPECT_TRUE(fs::is_empty(dir.path + "/abandoned"));
  }
  {  // Nothing kept: a failure with the counts, and nothing left behind.
    MapBuilderOptions o = options(dir.path + "/none", 32);
    o.min_z_m = 100.0;
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok());
    ASSERT_TRUE(w.feed(**b).ok());
    auto st = (*b)->finish();
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.error().find("no points kept"), std::string::npos) << st.error();
    EXPECT_TRUE(fs::is_empty(dir.path + "/none"));
  }
  {  // Cancelled from the progress callback after two tiles: no manifest, no tiles.
    auto b = MapBuilder::create(options(dir.path + "/cancel", 16));
    ASSERT_TRUE(b.ok());
    ASSERT_TRUE(w.feed(**b).ok());
    uint64_t last_done = 0, total = 0;
    auto st = (*b)->finish([&](const BuildProgress& p) {
      EXPECT_GT(p.tiles_done, last_done);
      last_done = p.tiles_done;
      total = p.tiles_total;
      return p.tiles_done < 2;
    });
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.error().find("cancelled"), std::string::npos);
    EXPECT_EQ(last_done, 2u);
    EXPECT_GT(total, 2u);
    EXPECT_TRUE(fs::is_empty(dir.path + "/cancel"));
  }
}

TEST(MapBuilder, RemovesSpillDirectoriesOfDeadProcesses) {
  TempDir dir("gmm_map_builder");
  // pid 2^22 + 1 is above Linux's pid_max limit: no such process can exist.
  const std::string stale = dir.path + "/.gmm_build_spill.4194305.0";
  const std::string live = dir.path + "/.gmm_build_spill." + std::to_string(getpid()) + ".999";
  fs::create_directories(stale);
  fs::create_directories(live);
  auto b = MapBuilder::create(options(dir.path));
  ASSERT_TRUE(b.ok());
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(live));  // a running process's directory is left alone
}

TEST(MapBuilder, RefusesToOverwriteUnlessAsked) {
  TempDir dir("gmm_map_builder");
  World big, small;
  big.plane(0.0, 20.0, 0.0, 20.0, 0.0);
  small.plane(0.0, 2.0, 0.0, 2.0, 1.0);
  ASSERT_TRUE(build(big, options(dir.path, 32)).ok());
  const size_t before = dir.entries().size();
  EXPECT_GT(before, 2u);
  auto again = MapBuilder::create(options(dir.path, 32));
  ASSERT_FALSE(again.ok());
  EXPECT_NE(again.error().find("already holds a map"), std::string::npos);
  MapBuilderOptions o = options(dir.path, 32);
  o.overwrite = true;
  auto store = build(small, o);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(dir.entries().size(), 2u);  // the old map's tiles are gone
  EXPECT_TRUE(store->verify().empty());
}

TEST(MapBuilder, OverwriteReplacesTheMapAndAlternatesTileFileNames) {
  TempDir dir("gmm_map_builder");
  World big, small;
  big.plane(0.0, 20.0, 0.0, 20.0, 0.0);
  small.plane(0.0, 2.0, 0.0, 2.0, 1.0);
  ASSERT_TRUE(build(big, options(dir.path, 32)).ok());
  MapBuilderOptions o = options(dir.path, 32);
  o.overwrite = true;
  for (const char* expected_name : {"tile_0_0.g1.gmt", "tile_0_0.gmt", "tile_0_0.g1.gmt"}) {
    auto store = build(small, o);
    ASSERT_TRUE(store.ok()) << store.error();
    ASSERT_EQ(store->tileIds(), (std::vector<TileId>{{0, 0}}));
    EXPECT_EQ(store->tileInfo({0, 0})->file_name, expected_name);
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"manifest.gmm", expected_name}));
    auto map = store->loadAll();
    ASSERT_TRUE(map.ok()) << map.error();
    const auto g = cellAt(*map, 1.0, 1.0);
    ASSERT_EQ(g.size(), 1);
    EXPECT_NEAR(g.component(0).mean_m, 1.0, 0.01);  // the small world's height
  }
}

TEST(MapBuilder, FailedOverwriteLeavesTheOldMapByteIdentical) {
  TempDir dir("gmm_map_builder");
  World old_world, new_world;
  old_world.plane(0.0, 12.0, 0.0, 12.0, 0.5);
  new_world.plane(0.0, 20.0, 0.0, 20.0, 2.0);  // 4 x 4 tiles of 6.4 m
  ASSERT_TRUE(build(old_world, options(dir.path, 32)).ok());
  const auto old_files = snapshot(dir.path);
  ASSERT_GT(old_files.size(), 2u);
  MapBuilderOptions o = options(dir.path, 32);
  o.overwrite = true;
  o.threads = 1;

  {  // Pass 1: the staging directory vanishes (an I/O error) while spill files are flushed.
    MapBuilderOptions small_buffer = o;
    small_buffer.spill_buffer_bytes = size_t{1} << 20;
    auto b = MapBuilder::create(small_buffer);
    ASSERT_TRUE(b.ok()) << b.error();
    const auto staging = stagingDirectories(dir.path);
    ASSERT_EQ(staging.size(), 1u);
    fs::remove_all(staging[0]);
    Status s = new_world.feed(**b, 500);
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.error().find("spill file"), std::string::npos) << s.error();
    EXPECT_FALSE((*b)->finish().ok());
    b->reset();
    expectIntactMap(dir.path, old_files);
  }
  {  // Pass 2: the staging directory vanishes after the first tile.
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok()) << b.error();
    ASSERT_TRUE(new_world.feed(**b).ok());
    expectIntactMap(dir.path, old_files);  // during the build too
    // The worker is on the next tile meanwhile, possibly creating a file in the directory:
    // removeWhileInUse() makes sure it is gone when the callback returns (a plain remove_all
    // may fail then, and throw).
    auto st = (*b)->finish([&](const BuildProgress& p) {
      if (p.tiles_done == 1) removeWhileInUse(stagingDirectories(dir.path).at(0));
      return true;
    });
    ASSERT_FALSE(st.ok());  // the next tile's spill file or tile file (or the journal) is gone
    EXPECT_TRUE(st.error().find("spill file") != std::string::npos ||
                st.error().find("cannot write") != std::string::npos)
        << st.error();
    EXPECT_NE(st.error().find("staging directory"), std::string::npos) << st.error();
    EXPECT_TRUE(stagingDirectories(dir.path).empty());
    expectIntactMap(dir.path, old_files);
  }
  {  // Pass 2: cancelled after two tiles.
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok()) << b.error();
    ASSERT_TRUE(new_world.feed(**b).ok());
    auto st = (*b)->finish([](const BuildProgress& p) { return p.tiles_done < 2; });
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.error().find("cancelled"), std::string::npos) << st.error();
    expectIntactMap(dir.path, old_files);
  }
  {  // The swap: the last tile cannot be moved in (a directory holds its name), so the tiles
     // already moved are taken out again.
    const std::string obstacle = dir.path + "/tile_3_3.g1.gmt";
    fs::create_directories(obstacle + "/inside");
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok()) << b.error();
    ASSERT_TRUE(new_world.feed(**b).ok());
    auto st = (*b)->finish();
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.error().find("cannot move tile file"), std::string::npos) << st.error();
    EXPECT_TRUE(stagingDirectories(dir.path).empty());
    expectIntactMap(dir.path, old_files);
    fs::remove_all(obstacle);
  }
  {  // Nothing kept.
    MapBuilderOptions none = o;
    none.min_z_m = 100.0;
    auto b = MapBuilder::create(none);
    ASSERT_TRUE(b.ok()) << b.error();
    ASSERT_TRUE(new_world.feed(**b).ok());
    ASSERT_FALSE((*b)->finish().ok());
    expectIntactMap(dir.path, old_files);
  }
  EXPECT_EQ(dir.entries().size(), old_files.size());  // no staging directory left anywhere
  auto store = build(new_world, o);                   // and then a build that succeeds
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->tileIds().size(), 16u);
  EXPECT_TRUE(store->verify().empty());
  EXPECT_EQ(dir.entries().size(), 17u);
}

/// For the tests of a pass 2 that goes wrong at each of its tiles in turn: a directory with a
/// small map (2 x 2 tiles), and a world of 4 x 4 tiles of 16 cells to overwrite it with.
struct FailingOverwrite {
  FailingOverwrite() {
    World old_world;
    old_world.plane(0.0, 6.4, 0.0, 6.4, 0.5, 0.1);
    world.plane(0.0, 12.8, 0.0, 12.8, 2.0, 0.1);
    EXPECT_TRUE(build(old_world, options(dir.path, 16)).ok());
    old_files = snapshot(dir.path);
    EXPECT_EQ(old_files.size(), 5u);
  }
  /// Overwrites the map with `world` on `threads` workers, with `progress` as the callback.
  Result<MapBuildStats> overwrite(int threads, const BuildProgressCallback& progress) const {
    MapBuilderOptions o = options(dir.path, 16);
    o.overwrite = true;
    o.threads = threads;
    auto b = MapBuilder::create(o);
    if (!b) return Result<MapBuildStats>::failure("create: " + b.error());
    Status s = world.feed(**b);
    if (!s) return Result<MapBuildStats>::failure("feed: " + s.error());
    return (*b)->finish(progress);
  }
  /// What a user is guaranteed after a failed build: the old map, byte-identical, and no
  /// staging directory (nor anything else) left behind.
  void expectOldMapOnly() const {
    expectIntactMap(dir.path, old_files);
    EXPECT_EQ(dir.entries().size(), old_files.size()) << "a staging directory is left";
  }

  TempDir dir{"gmm_map_builder"};
  World world;
  std::map<std::string, std::vector<uint8_t>> old_files;
  static constexpr uint64_t kTiles = 16;
};

TEST(MapBuilder, StagingDirectoryVanishingAtAnyTileFailsTheBuildCleanly) {
  // The staging directory is removed after tile k, for every k (the last: every tile is written
  // and the swap finds no staging directory), while the workers go on. Regression: a progress
  // callback doing this used to make finish() throw past its running workers (std::terminate).
  FailingOverwrite f;
  for (int threads : {1, 4}) {
    for (uint64_t k = 1; k <= FailingOverwrite::kTiles; ++k) {
      SCOPED_TRACE("threads " + std::to_string(threads) + ", removed after tile " +
                   std::to_string(k));
      uint64_t calls = 0;
      auto st = f.overwrite(threads, [&](const BuildProgress& p) {
        ++calls;
        EXPECT_EQ(p.tiles_total, FailingOverwrite::kTiles);
        if (p.tiles_done == k) removeWhileInUse(stagingDirectories(f.dir.path).at(0));
        return true;
      });
      ASSERT_FALSE(st.ok());
      EXPECT_NE(st.error().find("staging directory"), std::string::npos) << st.error();
      EXPECT_NE(st.error().find("disappeared during the build"), std::string::npos) << st.error();
      EXPECT_TRUE(st.error().find("spill file") != std::string::npos ||
                  st.error().find("cannot write") != std::string::npos)
          << st.error();
      EXPECT_GE(calls, k);
      f.expectOldMapOnly();
    }
  }
  // The same with a plain, throwing remove_all (the original test's callback): it races with
  // the worker writing into the directory, so either the directory goes (the build fails for
  // it) or remove_all throws (the build fails for that). Either way: a failure with a reason,
  // the workers joined, the old map byte-identical.
  for (uint64_t k = 1; k <= FailingOverwrite::kTiles; ++k) {
    SCOPED_TRACE("plain remove_all, removed after tile " + std::to_string(k));
    auto st = f.overwrite(1, [&](const BuildProgress& p) {
      if (p.tiles_done == k) fs::remove_all(stagingDirectories(f.dir.path).at(0));
      return true;
    });
    ASSERT_FALSE(st.ok());
    EXPECT_TRUE(st.error().find("disappeared during the build") != std::string::npos ||
                st.error().find("progress callback threw") != std::string::npos)
        << st.error();
    f.expectOldMapOnly();
  }
  ASSERT_TRUE(f.overwrite(4, {}).ok());  // the directory is usable: a build then succeeds
  auto store = MapStore::open(f.dir.path);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->tileIds().size(), FailingOverwrite::kTiles);
}

TEST(MapBuilder, ProgressCallbackThatThrowsFailsTheBuildCleanly) {
  // Regression: an exception from the callback left finish() with its workers still joinable,
  // and destroying them called std::terminate. It is a failure with the exception's text now.
  FailingOverwrite f;
  for (int threads : {1, 4}) {
    for (uint64_t k : {uint64_t{1}, uint64_t{8}, FailingOverwrite::kTiles}) {
      SCOPED_TRACE("threads " + std::to_string(threads) + ", throws at tile " + std::to_string(k));
      const std::string what = "callback failure at tile " + std::to_string(k);
      auto st = f.overwrite(threads, [&](const BuildProgress& p) -> bool {
        if (p.tiles_done == k) throw std::runtime_error(what);
        return true;
      });
      ASSERT_FALSE(st.ok());
      EXPECT_NE(st.error().find("progress callback threw: " + what), std::string::npos)
          << st.error();
      f.expectOldMapOnly();
    }
  }
  auto st = f.overwrite(2, [](const BuildProgress&) -> bool { throw 42; });
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().find("unknown type"), std::string::npos) << st.error();
  f.expectOldMapOnly();
  // Once the map is committed a throwing callback (the kDone call) cannot fail the build.
  st = f.overwrite(2, [](const BuildProgress& p) -> bool {
    if (p.stage == BuildProgress::Stage::kDone) throw std::runtime_error("after the commit");
    return true;
  });
  ASSERT_TRUE(st.ok()) << st.error();
  auto store = MapStore::open(f.dir.path);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->tileIds().size(), FailingOverwrite::kTiles);
  EXPECT_EQ(f.dir.entries().size(), FailingOverwrite::kTiles + 1);
}

/// Writes a staging directory as a build killed during the swap leaves it (journal: `names`).
void writeDeadStaging(const std::string& dir, const std::vector<std::string>& names) {
  // pid 2^22 + 1 is above Linux's pid_max limit: no such process can exist.
  const std::string staging = dir + "/.gmm_build.4194305.0";
  fs::create_directories(staging + "/spill");
  std::ofstream(staging + "/spill/t_0_0.spill") << "spill";
  std::ofstream journal(staging + "/journal");
  journal << "gmm_build journal 1\n";
  for (const std::string& n : names) journal << n << "\n";
}

TEST(MapBuilder, RecoversFromABuildKilledDuringTheSwap) {
  TempDir dir("gmm_map_builder"), other("gmm_map_builder");
  World old_world, new_world;
  old_world.plane(0.0, 12.0, 0.0, 12.0, 0.5);  // 2 x 2 tiles of 6.4 m
  new_world.plane(0.0, 20.0, 0.0, 20.0, 2.0);  // 4 x 4 tiles
  ASSERT_TRUE(build(old_world, options(dir.path, 32)).ok());
  ASSERT_TRUE(build(new_world, options(other.path, 32)).ok());
  const auto old_files = snapshot(dir.path);
  const auto new_files = snapshot(other.path);
  auto old_manifest = readManifest(dir.path);
  auto new_manifest = readManifest(other.path);
  ASSERT_TRUE(old_manifest.ok() && new_manifest.ok());
  std::vector<std::string> journal;
  for (TileInfo& t : new_manifest->tiles) {
    t.file_name = t.file_name.substr(0, t.file_name.size() - 4) + ".g1.gmt";
    journal.push_back(t.file_name);
  }
  for (const TileInfo& t : old_manifest->tiles) journal.push_back(t.file_name);
  auto moveNewTilesIn = [&](size_t count) {
    for (size_t i = 0; i < count; ++i) {
      const TileInfo& t = new_manifest->tiles[i];
      ASSERT_TRUE(
          writeFileAtomic(dir.path + "/" + t.file_name, new_files.at(tileFileName(t.id))).ok());
    }
  };
  MapBuilderOptions o = options(dir.path, 32);
  o.overwrite = true;

  // Killed while moving tiles in (step 3): the old map is whole; the next build takes the new
  // tiles out again.
  moveNewTilesIn(5);
  writeDeadStaging(dir.path, journal);
  auto mid = MapStore::open(dir.path);
  ASSERT_TRUE(mid.ok()) << mid.error();
  EXPECT_TRUE(mid->verify().empty());
  {
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok()) << b.error();
    EXPECT_EQ(stagingDirectories(dir.path).size(), 1u);  // the new builder's own
  }
  expectIntactMap(dir.path, old_files);
  EXPECT_TRUE(stagingDirectories(dir.path).empty());

  // Killed after the commit, while deleting the old tiles (step 5): the new map is whole; the
  // next build deletes the rest of the old tiles.
  moveNewTilesIn(new_manifest->tiles.size());
  ASSERT_TRUE(writeManifest(dir.path, *new_manifest).ok());
  fs::remove(dir.path + "/" + old_manifest->tiles[0].file_name);
  writeDeadStaging(dir.path, journal);
  const auto committed = snapshot(dir.path);
  {
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok()) << b.error();
  }
  auto store = MapStore::open(dir.path);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_TRUE(store->verify().empty());
  EXPECT_EQ(store->tileIds().size(), 16u);
  const auto after = snapshot(dir.path);
  EXPECT_EQ(after.size(), 17u);  // the manifest and the new tiles only
  for (const auto& [name, bytes] : after) EXPECT_TRUE(committed.at(name) == bytes) << name;
  EXPECT_TRUE(stagingDirectories(dir.path).empty());

  // Killed in pass 2 (no journal yet): the staging directory simply goes.
  writeDeadStaging(dir.path, {});
  fs::remove(dir.path + "/.gmm_build.4194305.0/journal");
  std::ofstream(dir.path + "/.gmm_build.4194305.0/tile_0_0.gmt") << "half a tile";
  EXPECT_FALSE(MapStore::open(dir.path + "/.gmm_build.4194305.0").ok());  // never a map
  {
    auto b = MapBuilder::create(o);
    ASSERT_TRUE(b.ok()) << b.error();
  }
  EXPECT_TRUE(snapshot(dir.path) == after);
  EXPECT_TRUE(stagingDirectories(dir.path).empty());
}

TEST(MapBuilder, OneBuilderPerOutputDirectory) {
  TempDir dir("gmm_map_builder");
  World w;
  w.plane(0.0, 2.0, 0.0, 2.0, 0.0);
  auto first = MapBuilder::create(options(dir.path));
  ASSERT_TRUE(first.ok()) << first.error();
  auto second = MapBuilder::create(options(dir.path));
  ASSERT_FALSE(second.ok());
  EXPECT_NE(second.error().find("in use by another map build"), std::string::npos)
      << second.error();
  EXPECT_EQ(stagingDirectories(dir.path).size(), 1u);  // the first one's, left alone
  ASSERT_TRUE(w.feed(**first).ok());
  ASSERT_TRUE((*first)->finish().ok());  // finish() releases the directory
  MapBuilderOptions o = options(dir.path);
  o.overwrite = true;
  EXPECT_TRUE(MapBuilder::create(o).ok());
}

TEST(MapBuilder, OptionsValidateNamesTheField) {
  MapBuilderOptions o;
  EXPECT_NE(o.validate().find("output_directory"), std::string::npos);
  o.output_directory = "/tmp/x";
  EXPECT_TRUE(o.validate().empty());
  o.blur_radius_cells = 20;
  EXPECT_NE(o.validate().find("blur_radius_cells"), std::string::npos);
  o = MapBuilderOptions();
  o.output_directory = "/tmp/x";
  o.max_range_m = 0.5;
  EXPECT_NE(o.validate().find("max_range_m"), std::string::npos);
  o = MapBuilderOptions();
  o.output_directory = "/tmp/x";
  o.em.max_components = 0;
  EXPECT_NE(o.validate().find("em: max_components"), std::string::npos);
  auto b = MapBuilder::create(o);
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.error().find("invalid map builder options"), std::string::npos);
}

}  // namespace
}  // namespace gmm_localization
