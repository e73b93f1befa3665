// The map builder's reflectivity layer (core/map/reflectivity_layer.h): a synthetic road of
// known intensities seen from a known vehicle pose. The map must hold the scaled intensities of
// the ground returns and nothing else, say so in its manifest, and leave the height layer's
// output as it was.
#include <cmath>
#include <filesystem>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/mapping/map_builder.h"
#include "support/temp_dir.h"

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

constexpr double kGroundZ = 10.0;  // the road's map-frame height, the vehicle frame's too
constexpr float kAsphalt = 11.f, kPaint = 110.f, kWall = 60.f;
constexpr double kStep = 0.04;  // lattice spacing [m]: 25 returns per 0.2 m cell

/// A road seen from a vehicle at (5, 5, kGroundZ) (sensor 2 m above it): ground returns with
/// 1 cm height noise and 1 unit intensity noise on x, y in [0, 10]: asphalt, a 0.15 m paint
/// stripe at x in [5, 5.15) and a 1 m painted block at x in [2, 3); a wall above the ground
/// band; a patch 0.2 m below the vehicle (inside the band, kept) and one 0.4 m above it
/// (outside, dropped); ground 45 m away (beyond the ground range, dropped).
class Road {
 public:
  Road() {
    for (double x = kStep / 2; x < 10.0; x += kStep) {
      for (double y = kStep / 2; y < 10.0; y += kStep) {
        const bool paint = (x >= 5.0 && x < 5.15) || (x >= 2.0 && x < 3.0);
        add(x, y, kGroundZ, paint ? kPaint : kAsphalt, &ground);
      }
    }
    for (double y = 2.0 + kStep / 2; y < 8.0; y += kStep) {
      for (double z = kGroundZ + 0.5; z < kGroundZ + 3.0; z += kStep)
        add(11.02, y, z, kWall, &not_ground);
    }
    patch(12.0, kGroundZ - 0.2, &ground);      // kept: levelled -0.2 m
    patch(14.0, kGroundZ + 0.4, &not_ground);  // dropped: levelled +0.4 m
    patch(50.0, kGroundZ, &not_ground);        // dropped: 45 m from the vehicle
  }

  /// Batches of 5000 points; `full`: with intensities and the vehicle origin.
  std::vector<PointBatch> batches(bool full) const {
    std::vector<PointBatch> out;
    for (size_t i = 0; i < points_.size(); i += 5000) {
      PointBatch b;
      const size_t end = std::min(points_.size(), i + 5000);
      b.points_m.assign(points_.begin() + i, points_.begin() + end);
      b.has_sensor_origin = true;
      b.sensor_origin_m = Eigen::Vector3d(5.0, 5.0, kGroundZ + 2.0);
      if (full) {
        b.intensity.assign(intensity_.begin() + i, intensity_.begin() + end);
        b.has_vehicle_origin = true;
        b.vehicle_origin_m = Eigen::Vector3d(5.0, 5.0, kGroundZ);
      }
      out.push_back(std::move(b));
    }
    return out;
  }

  size_t ground = 0, not_ground = 0;

 private:
  void add(double x, double y, double z, float intensity, size_t* count) {
    points_.emplace_back(x, y, z + height_noise_(rng_));
    intensity_.push_back(intensity + intensity_noise_(rng_));
    ++*count;
  }
  void patch(double x0, double z, size_t* count) {
    for (double x = x0 + kStep / 2; x < x0 + 1.0; x += kStep)
      for (double y = kStep / 2; y < 1.0; y += kStep) add(x, y, z, kAsphalt, count);
  }

  std::mt19937 rng_{7};
  std::normal_distribution<float> height_noise_{0.f, 0.01f}, intensity_noise_{0.f, 1.f};
  std::vector<Eigen::Vector3f> points_;
  std::vector<float> intensity_;
};

MapBuilderOptions options(const std::string& dir, MapLayer layer) {
  MapBuilderOptions o;
  o.output_directory = dir;
  o.geometry.tile_size_cells = 64;
  o.layer = layer;
  o.reflectivity.ground_min_m = -0.25;
  o.reflectivity.ground_max_m = 0.35;
  return o;
}

Result<MapBuildStats> build(const MapBuilderOptions& o, const std::vector<PointBatch>& batches) {
  auto b = MapBuilder::create(o);
  if (!b) return Result<MapBuildStats>::failure(b.error());
  for (const PointBatch& batch : batches) {
    Status s = (*b)->addBatch(batch);
    if (!s) return Result<MapBuildStats>::failure(s.error());
  }
  return (*b)->finish();
}

std::map<std::string, std::vector<uint8_t>> files(const std::string& dir) {
  std::map<std::string, std::vector<uint8_t>> out;
  for (const auto& e : fs::directory_iterator(dir))
    out[e.path().filename()] = *readFileBytes(e.path());
  return out;
}

GaussianMixture1D cellAt(const GmmMap& map, double x, double y) {
  const GaussianMixture1D* g = map.cell(map.geometry().cellAt(x, y));
  return g ? *g : GaussianMixture1D();
}

TEST(MapBuilderReflectivity, CellsHoldTheScaledIntensitiesOfTheGroundReturnsOnly) {
  TempDir dir("gmm_reflectivity");
  const Road road;
  const MapBuilderOptions o = options(dir.path, MapLayer::kReflectivity);
  auto stats = build(o, road.batches(true));
  ASSERT_TRUE(stats.ok()) << stats.error();
  EXPECT_EQ(stats->kept_points, road.ground);
  EXPECT_EQ(stats->dropped_not_ground, road.not_ground);
  EXPECT_EQ(stats->dropped_range + stats->dropped_height + stats->dropped_invalid, 0u);

  auto store = MapStore::open(dir.path);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->manifest().format_version, 3);
  EXPECT_EQ(store->layer(), MapLayer::kReflectivity);
  EXPECT_EQ(store->reflectivity().metres_per_unit, 0.02);
  EXPECT_EQ(store->reflectivity().ground_height_m, 0.0);
  EXPECT_EQ(store->reflectivity().ground_min_m, -0.25);
  EXPECT_EQ(store->reflectivity().ground_max_m, 0.35);
  EXPECT_EQ(store->reflectivity().max_range_m, 40.0);
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok()) << map.error();

  const double asphalt = kAsphalt * 0.02, paint = kPaint * 0.02;
  // Beyond the blur's reach (one cell) of every paint edge: one component at the value. Columns
  // of cells i (x in [0.2 i, 0.2 i + 0.2)): 10..14 the painted block, 25 the stripe.
  auto kind = [](int i) { return i >= 10 && i <= 14 ? 1 : i == 25 ? 2 : 0; };
  int asphalt_cells = 0, paint_cells = 0;
  for (int i = 1; i < 49; ++i) {
    if (kind(i - 1) != kind(i) || kind(i + 1) != kind(i)) continue;  // at an edge
    ASSERT_NE(kind(i), 2);
    const double x = 0.2 * i + 0.1;
    for (double y = 0.1; y < 10.0; y += 0.2) {
      const auto g = cellAt(*map, x, y);
      ASSERT_EQ(g.size(), 1) << x << ", " << y;
      EXPECT_NEAR(g.component(0).mean_m, kind(i) ? paint : asphalt, 0.025) << x << ", " << y;
      ++(kind(i) ? paint_cells : asphalt_cells);
    }
  }
  EXPECT_EQ(paint_cells, 3 * 50);
  EXPECT_EQ(asphalt_cells, (8 + 8 + 22) * 50);
  // The stripe's cell, 80% paint: its heaviest component is the paint's.
  for (double y = 0.1; y < 10.0; y += 0.2) {
    const auto g = cellAt(*map, 5.1, y);
    ASSERT_GE(g.size(), 1);
    int heaviest = 0;
    for (int j = 1; j < g.size(); ++j)
      if (g.component(j).weight > g.component(heaviest).weight) heaviest = j;
    EXPECT_NEAR(g.component(heaviest).mean_m, paint, 0.05) << y;
  }
  // The patch 0.2 m below the vehicle is ground; the wall, the raised patch and the far ground
  // are absent.
  EXPECT_EQ(cellAt(*map, 12.5, 0.5).size(), 1);
  EXPECT_NEAR(cellAt(*map, 12.5, 0.5).component(0).mean_m, asphalt, 0.025);
  for (const auto& [x, y] :
       {std::pair<double, double>{11.02, 5.0}, {11.02, 2.1}, {14.5, 0.5}, {50.5, 0.5}}) {
    EXPECT_TRUE(cellAt(*map, x, y).empty()) << x << ", " << y;
  }
}

TEST(MapBuilderReflectivity, HeightMapOfTheSameBatchesIsUnchanged) {
  // The height layer reads only the points and the sensor origin: the batches with intensities
  // and vehicle origins make byte for byte the map the bare batches make, wall included.
  TempDir full("gmm_reflectivity"), bare("gmm_reflectivity");
  const Road road;
  auto a = build(options(full.path, MapLayer::kHeight), road.batches(true));
  auto b = build(options(bare.path, MapLayer::kHeight), road.batches(false));
  ASSERT_TRUE(a.ok() && b.ok()) << (a.ok() ? b.error() : a.error());
  EXPECT_EQ(a->kept_points, road.ground + road.not_ground);
  EXPECT_EQ(a->dropped_not_ground, 0u);
  EXPECT_TRUE(files(full.path) == files(bare.path));
  auto store = MapStore::open(full.path);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(store->layer(), MapLayer::kHeight);
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok()) << map.error();
  EXPECT_FALSE(cellAt(*map, 11.02, 5.0).empty()) << "the height layer keeps the wall";
  EXPECT_NEAR(cellAt(*map, 0.5, 0.5).component(0).mean_m, kGroundZ, 0.01);
}

TEST(MapBuilderReflectivity, BatchesWithoutIntensityOrVehicleFailWithTheReason) {
  TempDir dir("gmm_reflectivity");
  const Road road;
  auto b = MapBuilder::create(options(dir.path, MapLayer::kReflectivity));
  ASSERT_TRUE(b.ok()) << b.error();
  PointBatch batch = road.batches(true).front();
  PointBatch no_intensity = batch;
  no_intensity.intensity.clear();
  Status s = (*b)->addBatch(no_intensity);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("batch 1: no intensity"), std::string::npos) << s.error();
  PointBatch short_intensity = batch;
  short_intensity.intensity.pop_back();
  s = (*b)->addBatch(short_intensity);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("4999 intensities for 5000 points"), std::string::npos) << s.error();
  PointBatch no_vehicle = batch;
  no_vehicle.has_vehicle_origin = false;
  s = (*b)->addBatch(no_vehicle);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("no vehicle pose"), std::string::npos) << s.error();
  // Nothing of them was taken, and the builder goes on.
  EXPECT_EQ((*b)->stats().batches, 0u);
  EXPECT_EQ((*b)->stats().input_points, 0u);
  ASSERT_TRUE((*b)->addBatch(batch).ok());
  EXPECT_EQ((*b)->stats().input_points, 5000u);
  EXPECT_TRUE((*b)->addBatch(PointBatch()).ok()) << "an empty batch needs nothing";

  // Through addAllBatches the reason names the input.
  struct Bare : PointBatchSource {
    std::vector<PointBatch> batches;
    size_t next_index = 0;
    Result<bool> next(PointBatch& out) override {
      if (next_index >= batches.size()) return false;
      out = batches[next_index++];
      return true;
    }
    std::string describe() const override { return "bare scans 'test'"; }
  } source;
  source.batches = road.batches(false);
  s = addAllBatches(source, **b);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().rfind("bare scans 'test': batch 1: no intensity", 0), 0u) << s.error();
}

TEST(MapBuilderReflectivity, OptionsAreValidatedAndDescribed) {
  MapBuilderOptions o = options("/tmp/unused", MapLayer::kReflectivity);
  EXPECT_EQ(o.validate(), "");
  const std::string d = o.describe();
  EXPECT_NE(d.find("layer=reflectivity metres_per_unit=0.02 ground_height=0m "
                   "ground_band=[-0.25,0.35]m ground_range=40m"),
            std::string::npos)
      << d;
  EXPECT_NE(options("/tmp/unused", MapLayer::kHeight).describe().find("layer=height"),
            std::string::npos);
  o.reflectivity.metres_per_unit = 0.0;
  EXPECT_EQ(o.validate(), "reflectivity.metres_per_unit=0 must be in (0, 100]");
  o.reflectivity.metres_per_unit = 0.02;
  o.reflectivity.ground_max_m = -0.5;
  EXPECT_EQ(o.validate(), "reflectivity.ground_max_m=-0.5 must exceed ground_min_m=-0.25");
  o.reflectivity.ground_max_m = 0.3;
  o.reflectivity.max_range_m = NAN;
  EXPECT_EQ(o.validate(), "reflectivity.max_range_m=nan must be in (0, 1000]");
  o.layer = MapLayer::kHeight;  // the reflectivity options do not matter then
  EXPECT_EQ(o.validate(), "");
}

}  // namespace
}  // namespace gmm_localization
