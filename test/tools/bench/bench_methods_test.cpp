// bench_registration --methods on a small generated KITTI-layout folder: a flat ground painted
// with 1 m patches of two intensities (asphalt and paint, as the reflectivity layer expects)
// and boxes standing on it, seen from four poses; the height map and its reflectivity layer are
// built from the same scans by build_map. Checks that a missing layer stops the run naming the
// directory and build_map, that scans without intensity are refused, and that a run with
// every method gives a row per method and window in which every match succeeds. No times are
// asserted.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "../../unit/support/temp_dir.h"

#ifndef GMM_BUILD_MAP_BINARY
#error "GMM_BUILD_MAP_BINARY (the path of the build_map executable) must be defined"
#endif
#ifndef GMM_BENCH_BINARY
#error "GMM_BENCH_BINARY (the path of the bench_registration executable) must be defined"
#endif

using gmm_localization::testing::TempDir;

namespace {

namespace fs = std::filesystem;

std::string readAll(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

int runCommand(const std::string& command, const std::string& log) {
  const int status = std::system((command + " >" + log + " 2>" + log + ".err").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Intensity of the painted ground at world x, y: 1 m patches, one in four paint (110), the
/// rest asphalt (11), by a hash of the patch.
float paint(double x, double y) {
  const auto ix = static_cast<int64_t>(std::floor(x)), iy = static_cast<int64_t>(std::floor(y));
  uint64_t h = static_cast<uint64_t>(ix * 73856093) ^ static_cast<uint64_t>(iy * 19349663);
  h *= 0x9E3779B97F4A7C15ull;  // mixed: the low bits of the products alone repeat every 4 m
  return (h >> 62) == 0 ? 110.0f : 11.0f;
}

struct Box {
  double x0, y0, x1, y1, h;
};

/// A KITTI-layout folder: velodyne/NNNNNN.bin (x,y,z,intensity, sensor frame on the ground)
/// and poses.txt (the sensor's poses), four scans along x with small turns.
void writeDataset(const std::string& dir, bool with_intensity) {
  fs::create_directories(dir + "/velodyne");
  const std::vector<Box> boxes = {{6, 9, 14, 15, 6},    {-12, 8, -4, 12, 9}, {18, -15, 24, -9, 4},
                                  {-8, -14, 0, -10, 7}, {30, 6, 33, 16, 5},  {-25, -4, -21, 3, 8}};
  std::ofstream poses(dir + "/poses.txt");
  poses.precision(12);
  for (int i = 0; i < 4; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(3.0 * i, 0.4 * i, 0.0);
    pose.linear() = Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) poses << (r || c ? " " : "") << pose.matrix()(r, c);
    poses << "\n";
    const Eigen::Isometry3d to_sensor = pose.inverse();
    std::vector<float> records;
    auto add = [&](const Eigen::Vector3d& world, float intensity) {
      const Eigen::Vector3d p = to_sensor * world;
      records.insert(records.end(), {float(p.x()), float(p.y()), float(p.z())});
      if (with_intensity) records.push_back(intensity);
    };
    const Eigen::Vector3d c = pose.translation();
    for (double x = -30.0; x <= 30.0; x += 0.2) {  // the ground within 30 m
      for (double y = -30.0; y <= 30.0; y += 0.2) {
        if (x * x + y * y > 900.0) continue;
        add(Eigen::Vector3d(c.x() + x, c.y() + y, 0.0), paint(c.x() + x, c.y() + y));
      }
    }
    for (const Box& b : boxes) {  // the four walls of each box
      for (double z = 0.1; z < b.h; z += 0.2) {
        for (double x = b.x0; x <= b.x1; x += 0.2) {
          add(Eigen::Vector3d(x, b.y0, z), 40.0f);
          add(Eigen::Vector3d(x, b.y1, z), 40.0f);
        }
        for (double y = b.y0; y <= b.y1; y += 0.2) {
          add(Eigen::Vector3d(b.x0, y, z), 40.0f);
          add(Eigen::Vector3d(b.x1, y, z), 40.0f);
        }
      }
    }
    char name[32];
    std::snprintf(name, sizeof name, "/velodyne/%06d.bin", i);
    std::ofstream f(dir + name, std::ios::binary);
    f.write(reinterpret_cast<const char*>(records.data()),
            static_cast<std::streamsize>(records.size() * sizeof(float)));  // little-endian hosts
  }
}

const std::string kBench = std::string(GMM_BENCH_BINARY) +
                           " --count 0 --peer-count 0 --exhaustive-every 0 --no-sizes --no-global"
                           " --no-memory-floor --seed 2";

}  // namespace

TEST(BenchMethods, EveryMethodOnTheSameScansAndAMissingLayer) {
  TempDir d("bench_methods_test");
  const std::string seq = d.path + "/seq", map = d.path + "/map", log = d.path + "/log";
  writeDataset(seq, true);
  const std::string build =
      std::string(GMM_BUILD_MAP_BINARY) + " --kitti " + seq + " --kitti-fields xyzi --output ";
  ASSERT_EQ(runCommand(build + map, log), 0) << readAll(log + ".err");

  // The height map alone: the other methods stop before any match, naming the layer's
  // directory and the command that builds it.
  const std::string base = kBench + " --map " + map + " --scans " + seq;
  EXPECT_EQ(runCommand(base + " --methods height,fused", log), 1);
  const std::string err = readAll(log + ".err");
  EXPECT_NE(err.find(map + "/reflectivity"), std::string::npos) << err;
  EXPECT_NE(err.find("build_map"), std::string::npos) << err;
  EXPECT_NE(err.find("--layer reflectivity"), std::string::npos) << err;
  EXPECT_EQ(readAll(log).find("## Match methods"), std::string::npos);

  ASSERT_EQ(runCommand(build + map + "/reflectivity --layer reflectivity", log), 0)
      << readAll(log + ".err");

  // Scans without intensity: refused with the reason.
  const std::string xyz = d.path + "/xyz";
  writeDataset(xyz, false);
  EXPECT_EQ(
      runCommand(kBench + " --map " + map + " --scans " + xyz + " --methods reflectivity", log), 1);
  EXPECT_NE(readAll(log + ".err").find("intensity"), std::string::npos) << readAll(log + ".err");

  // Every method: a row per method and window, every match within 0.5 m and 1 deg.
  const std::string out = d.path + "/out";
  ASSERT_EQ(runCommand(base + " --methods all --out " + out, log), 0) << readAll(log + ".err");
  const std::string text = readAll(log);
  EXPECT_NE(text.find("## Match methods (--methods)"), std::string::npos) << text;
  for (const char* window : {"paper", "tracking"}) {
    for (const char* method : {"height", "reflectivity", "fused"}) {
      const std::string row = std::string("| ") + window + " | " + method + " | 4 |";
      const size_t at = text.find(row);
      ASSERT_NE(at, std::string::npos) << row << "\n" << text;
      const std::string line = text.substr(at, text.find('\n', at) - at);
      EXPECT_NE(line.find("| 4/4 (100.0%) |"), std::string::npos) << line;
    }
  }
  // The CSV: the methods' registrations beside the height ones (matcher column), 4 each.
  std::map<std::string, int> per_matcher;
  std::istringstream csv(readAll(out + "/scans.csv"));
  std::string line;
  std::getline(csv, line);
  while (std::getline(csv, line)) {
    std::vector<std::string> f(1);  // section, window (quoted: it holds commas), matcher, ...
    bool quoted = false;
    for (char ch : line) {
      if (ch == '"') {
        quoted = !quoted;
      } else if (ch == ',' && !quoted) {
        f.emplace_back();
      } else {
        f.back() += ch;
      }
    }
    ASSERT_GE(f.size(), 3u) << line;
    ++per_matcher[f[1].substr(0, f[1].find(':')) + " / " + f[2]];
  }
  EXPECT_EQ(per_matcher["paper / gmm_localization"], 4);
  EXPECT_EQ(per_matcher["paper / gmm_localization reflectivity"], 4);
  EXPECT_EQ(per_matcher["tracking / gmm_localization fused"], 4);
  const std::string json = readAll(out + "/summary.json");
  EXPECT_NE(json.find("\"method\": \"fused\""), std::string::npos) << json;
  EXPECT_NE(json.find("ratio_to_height_match_total"), std::string::npos);
}
