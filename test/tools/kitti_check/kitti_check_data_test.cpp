// kitti_check reads the record layout the data has: x,y,z,intensity under velodyne/ (KITTI, as
// core/mapping/kitti_source.h) even when the point count makes the size fit x,y,z too, x,y,z
// for the keyframe dumps' NNNNNN/points.bin, a forced layout with --point-format, and a clear
// error for a size that is not a whole number of records. Poses without a scan are skipped;
// a KITTI calibration turns camera poses into Velodyne poses.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "../../unit/support/temp_dir.h"
#include "kitti_check/kitti_check_data.h"

using namespace gmm_localization;
using namespace gmm_localization::kitti_check;
using gmm_localization::testing::TempDir;

namespace {

namespace fs = std::filesystem;

using Point4 = std::array<float, 4>;

/// Little-endian float32 records of 4 (xyzi) or 3 (xyz) fields.
void writeScan(const std::string& path, const std::vector<Point4>& pts, bool xyzi) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream f(path, std::ios::binary);
  for (const Point4& p : pts) {
    for (int k = 0; k < (xyzi ? 4 : 3); ++k) {
      uint32_t bits;
      std::memcpy(&bits, &p[k], 4);
      const char le[4] = {char(bits), char(bits >> 8), char(bits >> 16), char(bits >> 24)};
      f.write(le, 4);
    }
  }
}

/// n distinct points with intensities that would read as coordinates if misaligned.
std::vector<Point4> points(int n, float base) {
  std::vector<Point4> out;
  for (int i = 0; i < n; ++i) out.push_back({base + i, 2.f * i - 5.f, 0.25f * i, 0.9f});
  return out;
}

void expectPoints(const Keyframe& k, const std::vector<Point4>& want) {
  ASSERT_EQ(k.points.size(), want.size()) << k.path;
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(k.points[i], Eigen::Vector3f(want[i][0], want[i][1], want[i][2]))
        << k.path << " " << i;
  }
}

KittiInput input(const std::string& dir, KittiFields fields = KittiFields::kAuto) {
  KittiInput in;
  in.dir = dir;
  in.fields = fields;
  return in;
}

const char* kTwoPoses = "1 0 0 10 0 1 0 20 0 0 1 1\n0 -1 0 5 1 0 0 0 0 0 1 0\n";

}  // namespace

TEST(KittiCheckData, VelodyneScansAreXyziEvenWhenTheSizeFitsXyz) {
  TempDir d("kitti_check_data");
  // 6 and 3 points: 96 and 48 bytes, multiples of 12 as well as 16.
  const auto a = points(6, 1.f), b = points(3, 40.f);
  writeScan(d.path + "/velodyne/000000.bin", a, true);
  writeScan(d.path + "/velodyne/000001.bin", b, true);
  std::ofstream(d.path + "/poses.txt") << kTwoPoses;
  auto set = loadKeyframes(input(d.path));
  ASSERT_TRUE(set.ok()) << set.error();
  ASSERT_EQ(set->keyframes.size(), 2u);
  expectPoints(set->keyframes[0], a);
  expectPoints(set->keyframes[1], b);
  EXPECT_EQ(set->data.source.fields, KittiFields::kXyzi);
  EXPECT_FALSE(set->data.ambiguous);
  EXPECT_NE(describeData(set->data).find("x,y,z,intensity"), std::string::npos);
  EXPECT_NE(describeData(set->data).find("velodyne/"), std::string::npos);
  // The map is built with the same layout: 9 points, not 12.
  auto built = buildMap(set->data, {}, defaultMapOptions(d.path + "/map"));
  ASSERT_TRUE(built.ok()) << built.error();
  EXPECT_EQ(built->input_points, 9u);
}

TEST(KittiCheckData, KeyframeDumpsAreXyzAndTheLayoutCanBeForced) {
  TempDir d("kitti_check_data");
  // 4 points x 12 bytes = 48 bytes: fits 3 xyzi records too.
  const auto a = points(4, 1.f);
  writeScan(d.path + "/000000/points.bin", a, false);
  std::ofstream(d.path + "/graph.txt") << "v0 1 2 3 0 0 0 1\n";
  auto set = loadKeyframes(input(d.path));
  ASSERT_TRUE(set.ok()) << set.error();
  ASSERT_EQ(set->keyframes.size(), 1u);
  expectPoints(set->keyframes[0], a);
  EXPECT_EQ(set->data.source.fields, KittiFields::kXyz);
  EXPECT_NE(describeData(set->data).find("points.bin"), std::string::npos);
  EXPECT_NEAR(set->keyframes[0].truth.translation().x(), 1.0, 1e-12);

  // Forced: the same bytes as 3 xyzi records.
  auto forced = loadKeyframes(input(d.path, KittiFields::kXyzi));
  ASSERT_TRUE(forced.ok()) << forced.error();
  EXPECT_EQ(forced->keyframes[0].points.size(), 3u);
  EXPECT_NE(describeData(forced->data).find("--point-format xyzi"), std::string::npos);
}

TEST(KittiCheckData, FlatFilesByTheirSizeAndAGuessIsSaid) {
  TempDir d("kitti_check_data");
  // 000000.bin: 5 xyz points (60 bytes, not a multiple of 16): the set is xyz.
  writeScan(d.path + "/000000.bin", points(5, 1.f), false);
  writeScan(d.path + "/000001.bin", points(4, 9.f), false);  // 48 bytes: fits both
  std::ofstream(d.path + "/poses.txt") << kTwoPoses;
  auto set = loadKeyframes(input(d.path));
  ASSERT_TRUE(set.ok()) << set.error();
  EXPECT_EQ(set->data.source.fields, KittiFields::kXyz);
  EXPECT_FALSE(set->data.ambiguous);
  expectPoints(set->keyframes[1], points(4, 9.f));

  // Only sizes that fit both: KITTI's xyzi, flagged and explained.
  fs::remove(d.path + "/000000.bin");
  writeScan(d.path + "/000000.bin", points(3, 1.f), true);  // 48 bytes
  auto guessed = loadKeyframes(input(d.path));
  ASSERT_TRUE(guessed.ok()) << guessed.error();
  EXPECT_TRUE(guessed->data.ambiguous);
  EXPECT_EQ(guessed->data.source.fields, KittiFields::kXyzi);
  expectPoints(guessed->keyframes[0], points(3, 1.f));
  EXPECT_NE(describeData(guessed->data).find("--point-format xyz"), std::string::npos)
      << describeData(guessed->data);
}

TEST(KittiCheckData, SizeNotAMultipleOfTheRecordIsAnErrorNamingTheFile) {
  TempDir d("kitti_check_data");
  std::ofstream(d.path + "/poses.txt") << kTwoPoses;
  writeScan(d.path + "/velodyne/000000.bin", points(3, 1.f), true);
  // 2 xyzi points and a truncated third: 40 bytes, a multiple of neither.
  writeScan(d.path + "/velodyne/000001.bin", points(2, 1.f), true);
  {
    std::ofstream(d.path + "/velodyne/000001.bin", std::ios::app | std::ios::binary) << "12345678";
  }
  auto set = loadKeyframes(input(d.path));
  ASSERT_FALSE(set.ok());
  EXPECT_NE(set.error().find("000001.bin"), std::string::npos) << set.error();
  EXPECT_NE(set.error().find("40 bytes is not a multiple of 16"), std::string::npos) << set.error();

  // A forced layout that does not fit: 2 xyzi points (32 bytes) as xyz.
  fs::remove(d.path + "/velodyne/000001.bin");
  writeScan(d.path + "/velodyne/000001.bin", points(2, 1.f), true);
  auto forced = loadKeyframes(input(d.path, KittiFields::kXyz));
  ASSERT_FALSE(forced.ok());
  EXPECT_NE(forced.error().find("32 bytes is not a multiple of 12"), std::string::npos)
      << forced.error();

  // Flat files that fit neither layout.
  TempDir flat("kitti_check_data");
  std::ofstream(flat.path + "/poses.txt") << kTwoPoses;
  std::ofstream(flat.path + "/000000.bin") << std::string(20, 'x');
  auto neither = loadKeyframes(input(flat.path));
  ASSERT_FALSE(neither.ok());
  EXPECT_NE(neither.error().find("000000.bin"), std::string::npos) << neither.error();
}

TEST(KittiCheckData, PosesWithoutAScanAreSkippedAndCalibrationApplies) {
  TempDir d("kitti_check_data");
  writeScan(d.path + "/velodyne/000000.bin", points(3, 1.f), true);
  writeScan(d.path + "/velodyne/000002.bin", points(3, 1.f), true);
  // Camera-0 poses: identity, then 1 m along the camera's z (forward), then 2 m.
  std::ofstream(d.path + "/poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                          "1 0 0 0 0 1 0 0 0 0 1 1\n"
                                          "1 0 0 0 0 1 0 0 0 0 1 2\n";
  // Velodyne x forward = camera z, velodyne y left = -camera x, velodyne z up = -camera y.
  std::ofstream(d.path + "/calib.txt") << "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n"
                                          "Tr: 0 -1 0 0 0 0 -1 0 1 0 0 0\n";
  KittiInput in = input(d.path);
  in.calib_file = d.path + "/calib.txt";
  auto set = loadKeyframes(in);
  ASSERT_TRUE(set.ok()) << set.error();
  ASSERT_EQ(set->keyframes.size(), 2u);
  EXPECT_EQ(set->data.poses, 3u);
  EXPECT_EQ(set->data.missing, std::vector<int>{1});
  EXPECT_NE(describeData(set->data).find("1 of 3 poses have no scan file"), std::string::npos);
  // Scan 2 is 2 m ahead along the Velodyne's x in the map frame (the first Velodyne frame).
  EXPECT_TRUE(set->keyframes[1].truth.translation().isApprox(Eigen::Vector3d(2, 0, 0), 1e-9))
      << set->keyframes[1].truth.translation().transpose();
  EXPECT_TRUE(set->keyframes[1].truth.linear().isIdentity(1e-9));
}
