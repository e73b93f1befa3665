// bench_registration's data on KITTI-layout folders as users have them: velodyne/ scans read as
// x,y,z,intensity, poses without a scan file skipped and counted, the KITTI calibration applied
// as build_map --kitti-calib applies it, and the peers' target cloud from a configurable
// selection of mapping scans; the command line's new options and their defaults.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "../../unit/support/temp_dir.h"
#include "bench/bench_data.h"
#include "bench/bench_options.h"
#include "gmm_localization/core/mapping/kitti_source.h"

using namespace gmm_localization;
using namespace gmm_localization::bench;
using gmm_localization::testing::TempDir;

namespace {

namespace fs = std::filesystem;

void writeXyzi(const std::string& path, const std::vector<std::array<float, 4>>& pts) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream f(path, std::ios::binary);
  for (const auto& p : pts) {
    for (float v : p) {
      uint32_t bits;
      std::memcpy(&bits, &v, 4);
      const char le[4] = {char(bits), char(bits >> 8), char(bits >> 16), char(bits >> 24)};
      f.write(le, 4);
    }
  }
}

std::string scanName(const std::string& dir, int i) {
  char name[32];
  std::snprintf(name, sizeof name, "/velodyne/%06d.bin", i);
  return dir + name;
}

// A KITTI-like velodyne -> camera 0 transform (a rotation of axes plus a small offset).
const char* kCalib =
    "P0: 7.0e+02 0 6.0e+02 0 0 7.0e+02 1.8e+02 0 0 0 1 0\n"
    "Tr: -1.857739385241e-03 -9.999659513510e-01 -8.039975204516e-03 -4.784029760483e-03 "
    "-6.481465826011e-03 8.051860151134e-03 -9.999466081774e-01 -7.337429464231e-02 "
    "9.999773098287e-01 -1.805528627661e-03 -6.496203536139e-03 -3.339968064433e-01\n";

}  // namespace

TEST(BenchData, KittiFolderWithMissingScansAndACalibration) {
  TempDir d("bench_data");
  // Camera-0 poses along the camera's z (forward), 1 m apart; scans 0, 1, 3 and 5 exist.
  std::ofstream poses(d.path + "/poses.txt");
  for (int i = 0; i < 6; ++i) poses << "1 0 0 0 0 1 0 0 0 0 1 " << i << "\n";
  poses.close();
  std::ofstream(d.path + "/calib.txt") << kCalib;
  // 3 xyzi points per scan: 48 bytes, which would also parse as 4 xyz points.
  for (int i : {0, 1, 3, 5}) {
    writeXyzi(scanName(d.path, i),
              {{{1.f * i, 2.f, 3.f, 0.5f}, {4.f, 5.f, 6.f, 0.25f}, {7.f, 8.f, 9.f, 0.125f}}});
  }
  KittiInput in;
  in.dir = d.path;
  in.calib_file = d.path + "/calib.txt";
  KittiScans data;
  auto scans = loadScans(in, 0, &data);
  ASSERT_TRUE(scans.ok()) << scans.error();
  EXPECT_EQ(data.poses, 6u);
  EXPECT_EQ(data.missing, (std::vector<int>{2, 4}));
  ASSERT_EQ(scans->size(), 4u);
  EXPECT_EQ(data.source.fields, KittiFields::kXyzi);
  EXPECT_EQ(scans->at(2).index, 3);
  ASSERT_EQ(scans->at(2).points.size(), 3u);
  EXPECT_EQ(scans->at(2).points[0], Eigen::Vector3f(3.f, 2.f, 3.f));
  EXPECT_EQ(scans->at(2).points[2], Eigen::Vector3f(7.f, 8.f, 9.f));
  // Truth as build_map --kitti-calib: Tr^-1 * pose * Tr, i.e. 3 m along the Velodyne's x
  // (forward), level.
  auto tr = readKittiCalibTr(in.calib_file);
  ASSERT_TRUE(tr.ok());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0, 0, 3);
  const Eigen::Isometry3d want = tr->inverse() * pose * tr.value();
  EXPECT_TRUE(scans->at(2).truth.isApprox(want, 1e-12));
  EXPECT_NEAR(scans->at(2).truth.translation().x(), 3.0, 0.01);
  EXPECT_NEAR(scans->at(2).truth.translation().z(), 0.0, 0.05);

  // --count picks evenly among the scans that exist.
  auto two = loadScans(in, 2, nullptr);
  ASSERT_TRUE(two.ok()) << two.error();
  ASSERT_EQ(two->size(), 2u);
  EXPECT_EQ(two->at(0).index, 0);
  EXPECT_EQ(two->at(1).index, 3);

  // Without the calibration the poses are the sensor's: 3 m along z.
  in.calib_file.clear();
  auto raw = loadScans(in, 0, nullptr);
  ASSERT_TRUE(raw.ok()) << raw.error();
  EXPECT_NEAR(raw->at(2).truth.translation().z(), 3.0, 1e-12);

  // A missing calibration file is an error, not identity.
  in.calib_file = d.path + "/no_calib.txt";
  EXPECT_FALSE(loadScans(in, 0, nullptr).ok());
}

TEST(BenchData, PeerTargetSelection) {
  TempDir d("bench_data");
  // Mapping scans 0..9, 1 m apart along x, each one point 0.5 m above its sensor.
  std::ofstream poses(d.path + "/poses.txt");
  for (int i = 0; i < 10; ++i) poses << "1 0 0 " << i << " 0 1 0 0 0 0 1 0\n";
  poses.close();
  for (int i = 0; i < 10; ++i) writeXyzi(scanName(d.path, i), {{{0.f, 0.f, 0.5f, 1.f}}});
  KittiInput in;
  in.dir = d.path;
  auto mapping = openKittiInput(in);
  ASSERT_TRUE(mapping.ok()) << mapping.error();
  auto count = [&](const PeerTargetOptions& o) {
    auto t = targetCloud(mapping.value(), Eigen::Vector3d(5, 0, 0), 5, o);
    return t.ok() ? static_cast<int>(t->size()) : -1;
  };
  PeerTargetOptions o;
  o.voxel_m = 0.1;
  EXPECT_EQ(count(o), 2);  // default: indices 0 and 5 (multiples of 5)
  o.stride = 1;
  EXPECT_EQ(count(o), 10);
  o.exclude = 0;  // not the test scan itself
  EXPECT_EQ(count(o), 9);
  o.exclude = 2;  // not 3..7
  EXPECT_EQ(count(o), 5);
  o.exclude = -1;
  o.radius_m = 4.0;  // scans within 2 m: 3..7
  EXPECT_EQ(count(o), 5);
  o.stride = 5;
  o.exclude = 0;
  o.radius_m = 80.0;
  EXPECT_EQ(count(o), 1);  // only scan 0 is left
  o.exclude = 5;
  EXPECT_EQ(count(o), -1);  // none: an error
}

TEST(BenchOptions, DefaultsAndNewOptions) {
  auto parse = [](std::vector<std::string> args, BenchOptions& o) {
    args.insert(args.begin(), "bench_registration");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(&a[0]);
    bool help = false;
    return parseBenchOptions(static_cast<int>(argv.size()), argv.data(), o, help);
  };
  BenchOptions o;
  ASSERT_TRUE(parse({"--map", "m", "--scans", "s"}, o));
  EXPECT_EQ(o.track_offset_m, 1.5);
  EXPECT_EQ(o.track_offset_deg, 2.5);
  EXPECT_EQ(o.peer_target.stride, 5);
  EXPECT_EQ(o.peer_target.exclude, -1);
  EXPECT_EQ(o.peer_target.radius_m, 80.0);
  EXPECT_EQ(o.scans.fields, KittiFields::kAuto);
  EXPECT_TRUE(o.out_dir.empty());

  BenchOptions n;
  ASSERT_TRUE(parse({"--map",
                     "m",
                     "--scans",
                     "s",
                     "--mapping",
                     "s",
                     "--kitti-calib",
                     "c.txt",
                     "--poses",
                     "p.txt",
                     "--track-offset-m",
                     "0.75",
                     "--track-offset-deg",
                     "1",
                     "--peer-target-stride",
                     "1",
                     "--peer-target-exclude",
                     "0",
                     "--out",
                     "o",
                     "--point-format",
                     "xyzi"},
                    n));
  EXPECT_EQ(n.scans.calib_file, "c.txt");
  EXPECT_EQ(n.mapping.calib_file, "c.txt");  // one calibration for both
  EXPECT_EQ(n.scans.poses_file, "p.txt");
  EXPECT_TRUE(n.mapping.poses_file.empty());
  EXPECT_EQ(n.track_offset_m, 0.75);
  EXPECT_EQ(n.track_offset_deg, 1.0);
  EXPECT_EQ(n.peer_target.stride, 1);
  EXPECT_EQ(n.peer_target.exclude, 0);
  EXPECT_EQ(n.out_dir, "o");
  EXPECT_EQ(n.mapping.fields, KittiFields::kXyzi);

  // --methods: height first and always, duplicates once; all = the three.
  EXPECT_EQ(o.methods, std::vector<MatchMethod>{MatchMethod::kHeight});
  BenchOptions m;
  ASSERT_TRUE(parse({"--map", "m", "--scans", "s", "--methods", "fused,reflectivity,fused"}, m));
  EXPECT_EQ(m.methods, (std::vector<MatchMethod>{MatchMethod::kHeight, MatchMethod::kFused,
                                                 MatchMethod::kReflectivity}));
  ASSERT_TRUE(parse({"--map", "m", "--scans", "s", "--methods", "all"}, m));
  EXPECT_EQ(m.methods, (std::vector<MatchMethod>{MatchMethod::kHeight, MatchMethod::kReflectivity,
                                                 MatchMethod::kFused}));
  ASSERT_TRUE(parse({"--map", "m", "--scans", "s", "--methods", "height"}, m));
  EXPECT_EQ(m.methods, std::vector<MatchMethod>{MatchMethod::kHeight});

  BenchOptions bad;
  EXPECT_FALSE(parse({"--map", "m", "--scans", "s", "--methods", "height,intensity"}, bad));
  EXPECT_FALSE(parse({"--map", "m", "--scans", "s", "--methods", ""}, bad));
  EXPECT_FALSE(parse({"--map", "m", "--scans", "s", "--methods", "height,"}, bad));
  EXPECT_FALSE(parse({"--map", "m", "--scans", "s", "--track-offset-m", "x"}, bad));
  EXPECT_FALSE(parse({"--map", "m", "--scans", "s", "--peer-target-stride", "0"}, bad));
  EXPECT_FALSE(parse({"--map", "m", "--scans", "s", "--point-format", "xyzrgb"}, bad));
  EXPECT_NE(std::string(benchUsage()).find("--kitti-calib"), std::string::npos);
}
