#include "gmm_localization/core/mapping/kitti_source.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/mapping/map_builder.h"
#include "support/temp_dir.h"

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;

using testing::TempDir;

void writeScan(const std::string& path, const std::vector<std::array<float, 4>>& pts, bool xyzi) {
  std::ofstream f(path, std::ios::binary);
  for (const auto& p : pts) {
    for (int k = 0; k < (xyzi ? 4 : 3); ++k) {
      uint32_t bits;
      std::memcpy(&bits, &p[k], 4);
      const char le[4] = {char(bits), char(bits >> 8), char(bits >> 16), char(bits >> 24)};
      f.write(le, 4);
    }
  }
}

TEST(KittiSource, ReadsBothPoseFormatsAndLayouts) {
  TempDir d("gmm_kitti");
  // KITTI odometry layout: velodyne/NNNNNN.bin (xyzi) and poses.txt with 3x4 rows. Scan 0
  // holds 3 points (48 bytes, ambiguous by size): under velodyne/ it is read as xyzi.
  fs::create_directory(d.path + "/velodyne");
  writeScan(d.path + "/velodyne/000000.bin",
            {{1.f, 0.f, 0.f, 0.5f}, {1.f, 0.f, 0.f, 0.5f}, {1.f, 0.f, 0.f, 0.5f}}, true);
  writeScan(d.path + "/velodyne/000001.bin", {{1.f, 0.f, 0.f, 0.5f}, {0.f, 2.f, 0.f, 0.1f}}, true);
  std::ofstream(d.path + "/poses.txt") << "1 0 0 10 0 1 0 20 0 0 1 1\n"
                                          "0 -1 0 5 1 0 0 0 0 0 1 0\n";
  KittiSourceOptions o;
  o.scans_directory = d.path;
  auto src = KittiScanSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  ASSERT_EQ((*src)->sizeHint(), 2u);
  PointBatch b;
  ASSERT_TRUE(*(*src)->next(b));
  ASSERT_EQ(b.points_m.size(), 3u);
  EXPECT_TRUE(b.points_m[0].isApprox(Eigen::Vector3f(11.f, 20.f, 1.f)));
  EXPECT_TRUE(b.sensor_origin_m.isApprox(Eigen::Vector3d(10.0, 20.0, 1.0)));
  ASSERT_TRUE(*(*src)->next(b));
  ASSERT_EQ(b.points_m.size(), 2u);
  EXPECT_TRUE(b.points_m[0].isApprox(Eigen::Vector3f(5.f, 1.f, 0.f)));  // rotated 90 deg
  EXPECT_FALSE(*(*src)->next(b));

  // Keyframe layout: NNNNNN/points.bin (xyz) and graph lines with ids. Scan 0 holds 4 points
  // (48 bytes, ambiguous by size): as a points.bin it is read as xyz.
  TempDir k("gmm_kitti");
  for (int i : {0, 3}) {
    fs::create_directory(k.path + "/00000" + std::to_string(i));
    writeScan(k.path + "/00000" + std::to_string(i) + "/points.bin",
              i == 0
                  ? std::vector<std::array<float, 4>>(4, {1.f, 0.f, 0.f, 0.f})
                  : std::vector<std::array<float, 4>>{{1.f, 0.f, 0.f, 0.f}, {2.f, 0.f, 0.f, 0.f}},
              false);  // xyz only
  }
  std::ofstream(k.path + "/graph.txt") << "v0 0 0 0 0 0 0 1\nv3 1 2 3 0 0 0.7071068 0.7071068\n";
  KittiSourceOptions ko;
  ko.scans_directory = k.path;
  auto ks = KittiScanSource::open(ko);
  ASSERT_TRUE(ks.ok()) << ks.error();
  ASSERT_EQ((*ks)->scans().size(), 2u);
  EXPECT_EQ((*ks)->scans()[1].index, 3);
  ASSERT_TRUE(*(*ks)->next(b));
  EXPECT_EQ(b.points_m.size(), 4u);
  ASSERT_TRUE(*(*ks)->next(b));
  EXPECT_TRUE(b.points_m[1].isApprox(Eigen::Vector3f(1.f, 4.f, 3.f), 1e-5f));
  ko.scans = {3, 1};  // scan 1 has neither a pose nor a file
  auto bad = KittiScanSource::open(ko);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("scan 1: no pose"), std::string::npos) << bad.error();
}

TEST(KittiSource, FieldLayoutDetectionAndErrors) {
  TempDir d("gmm_kitti");
  writeScan(d.path + "/a.bin", std::vector<std::array<float, 4>>(4, {1, 2, 3, 4}), false);  // 48 B
  auto ambiguous = readKittiScan(d.path + "/a.bin", KittiFields::kAuto);
  ASSERT_FALSE(ambiguous.ok());
  EXPECT_NE(ambiguous.error().find("give the layout explicitly"), std::string::npos);
  auto xyz = readKittiScan(d.path + "/a.bin", KittiFields::kXyz);
  ASSERT_TRUE(xyz.ok());
  EXPECT_EQ(xyz->size(), 4u);
  auto xyzi = readKittiScan(d.path + "/a.bin", KittiFields::kXyzi);
  ASSERT_TRUE(xyzi.ok());
  EXPECT_EQ(xyzi->size(), 3u);
  writeScan(d.path + "/b.bin", std::vector<std::array<float, 4>>(5, {1, 2, 3, 4}), true);  // 80 B
  auto auto16 = readKittiScan(d.path + "/b.bin", KittiFields::kAuto);
  ASSERT_TRUE(auto16.ok());
  EXPECT_EQ(auto16->size(), 5u);
  EXPECT_FALSE(readKittiScan(d.path + "/b.bin", KittiFields::kXyz).ok());  // 80 % 12 != 0
  EXPECT_FALSE(readKittiScan(d.path + "/missing.bin", KittiFields::kAuto).ok());

  std::ofstream(d.path + "/bad_poses.txt") << "1 2 3\n";
  auto poses = readKittiPoses(d.path + "/bad_poses.txt");
  ASSERT_FALSE(poses.ok());
  EXPECT_NE(poses.error().find("line 1"), std::string::npos);
  std::ofstream(d.path + "/calib.txt")
      << "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 -1 0 0 0 0 -1 0 1 0 0 -0.3\n";
  auto tr = readKittiCalibTr(d.path + "/calib.txt");
  ASSERT_TRUE(tr.ok());
  EXPECT_TRUE((tr->linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(0, 0, 1)));

  auto list = parseIndexList("0,2,4-6");
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(*list, (std::vector<int>{0, 2, 4, 5, 6}));
  EXPECT_FALSE(parseIndexList("1,x").ok());
  EXPECT_FALSE(parseIndexList("5-3").ok());
}

TEST(KittiSource, XyziScansCarryIntensitiesAndTheScanFrameAsTheVehicle) {
  TempDir d("gmm_kitti");
  fs::create_directory(d.path + "/velodyne");
  writeScan(d.path + "/velodyne/000000.bin", {{1.f, 0.f, -1.7f, 11.f}, {0.f, 2.f, -1.7f, 110.f}},
            true);
  std::ofstream(d.path + "/poses.txt") << "1 0 0 10 0 1 0 20 0 0 1 1.73\n";
  KittiSourceOptions o;
  o.scans_directory = d.path;
  o.fields = KittiFields::kXyzi;
  auto src = KittiScanSource::open(o);
  ASSERT_TRUE(src.ok()) << src.error();
  PointBatch b;
  ASSERT_TRUE(*(*src)->next(b));
  EXPECT_TRUE(b.hasIntensity());
  EXPECT_EQ(b.intensity, (std::vector<float>{11.f, 110.f}));
  ASSERT_TRUE(b.has_vehicle_origin);
  EXPECT_TRUE(b.vehicle_origin_m.isApprox(Eigen::Vector3d(10.0, 20.0, 1.73)));
  // Levelled height above the scan's frame: -1.7 m, the ground of a Velodyne at 1.73 m.
  EXPECT_NEAR(b.points_m[1].z() - b.vehicle_origin_m.z(), -1.7, 1e-6);

  // xyz records carry none; readKittiScan clears what it was given.
  writeScan(d.path + "/xyz.bin", {{1.f, 2.f, 3.f, 0.f}}, false);
  std::vector<float> intensity = {5.f};
  auto xyz = readKittiScan(d.path + "/xyz.bin", KittiFields::kXyz, &intensity);
  ASSERT_TRUE(xyz.ok());
  EXPECT_TRUE(intensity.empty());
  auto xyzi = readKittiScan(d.path + "/velodyne/000000.bin", KittiFields::kXyzi, &intensity);
  ASSERT_TRUE(xyzi.ok());
  EXPECT_EQ(intensity, (std::vector<float>{11.f, 110.f}));
}

// Fuzz reproducer test/fuzz/regressions/kitti/oom_index_list_60_ranges_of_1e7: 60 ranges of
// 10^7 indices each (660 characters) made 6 x 10^8 ints (2.4 GB). Now the list as a whole holds
// at most kMaxIndexListSize = 10^7 indices, with an error naming the item that exceeds it.
TEST(KittiSource, IndexListTotalIsBounded) {
  std::string sixty;
  for (int i = 0; i < 60; ++i) sixty += (i ? ",0-" : "0-") + std::to_string(10000000);
  ASSERT_EQ(sixty.size(), 60u * 10 + 59);
  auto oom = parseIndexList(sixty);
  ASSERT_FALSE(oom.ok());
  EXPECT_NE(oom.error().find("holds more than 10000000 indices (0 before '0-10000000', which "
                             "adds 10000001)"),
            std::string::npos)
      << oom.error();
  EXPECT_LT(oom.error().size(), 200u) << "the long list is quoted in part";
  // Ranges that are each small but sum beyond the bound, and single indices past it.
  auto sum = parseIndexList("0-4999999,5000000-9999999,7");
  ASSERT_FALSE(sum.ok());
  EXPECT_NE(sum.error().find("10000000 before '7', which adds 1"), std::string::npos)
      << sum.error();
  auto repeats = parseIndexList("0-5999999,0-5999999");
  ASSERT_FALSE(repeats.ok());
  EXPECT_NE(repeats.error().find("holds more than"), std::string::npos) << repeats.error();
  // Exactly the bound is accepted.
  auto full = parseIndexList("0-4999999,5000000-9999999");
  ASSERT_TRUE(full.ok()) << full.error();
  ASSERT_EQ(full->size(), kMaxIndexListSize);
  EXPECT_EQ(full->back(), 9999999);
  // A range ending at INT_MAX stops there (no overflow of the loop index).
  auto top = parseIndexList("2147483646-2147483647");
  ASSERT_TRUE(top.ok()) << top.error();
  EXPECT_EQ(*top, (std::vector<int>{2147483646, 2147483647}));
}

// Real scans: five KITTI 07 keyframes (HDL-64E, sensor about 1.73 m above the road).
TEST(KittiRealData, MapHasAPlausibleGroundComponent) {
  const std::string dir = std::string(GMM_SHARED_DATA_DIR) + "/real/kitti07_keyframes";
  if (!fs::exists(dir + "/graph.txt")) {
    GTEST_SKIP() << "real data absent: " << dir << " (see ../shared/data/real/README.md)";
  }
  TempDir out("gmm_kitti");
  KittiSourceOptions ko;
  ko.scans_directory = dir;
  ko.fields = KittiFields::kXyz;  // the keyframes are x, y, z only
  auto src = KittiScanSource::open(ko);
  ASSERT_TRUE(src.ok()) << src.error();
  ASSERT_EQ((*src)->sizeHint(), 5u);
  MapBuilderOptions o;
  o.output_directory = out.path + "/map";
  auto builder = MapBuilder::create(o);
  ASSERT_TRUE(builder.ok()) << builder.error();
  ASSERT_TRUE(addAllBatches(**src, **builder).ok());
  auto stats = (*builder)->finish();
  ASSERT_TRUE(stats.ok()) << stats.error();
  EXPECT_GT(stats->kept_points, 100000u);
  auto store = MapStore::open(o.output_directory);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_TRUE(store->verify().empty());
  auto map = store->loadAll();
  ASSERT_TRUE(map.ok());
  // Around every keyframe (4-10 m away: outside the sensor's blind ring), the lowest component
  // of most cells is the road: tight, about 1.7 m below the sensor.
  for (const auto& scan : (*src)->scans()) {
    const Eigen::Vector3d p = scan.map_T_sensor.translation();
    std::vector<double> lowest;
    int cells = 0, tight_ground = 0;
    for (double dx = -10.0; dx <= 10.0; dx += 0.2) {
      for (double dy = -10.0; dy <= 10.0; dy += 0.2) {
        const double r = std::hypot(dx, dy);
        if (r < 4.0 || r > 10.0) continue;
        const GaussianMixture1D* g = map->cell(map->geometry().cellAt(p.x() + dx, p.y() + dy));
        if (!g || g->empty()) continue;
        ++cells;
        const GaussianComponent& low = g->component(0);
        lowest.push_back(low.mean_m - p.z());
        tight_ground += low.sigma_m < 0.06f && std::abs(low.mean_m - (p.z() - 1.73)) < 0.25;
      }
    }
    ASSERT_GT(cells, 1000) << "keyframe " << scan.index;
    std::nth_element(lowest.begin(), lowest.begin() + lowest.size() / 2, lowest.end());
    const double median = lowest[lowest.size() / 2];
    EXPECT_GT(median, -1.85) << "keyframe " << scan.index;
    EXPECT_LT(median, -1.45) << "keyframe " << scan.index;
    EXPECT_GT(tight_ground, cells * 3 / 10) << "keyframe " << scan.index;
  }
}

}  // namespace
}  // namespace gmm_localization
