// bench_registration on a KITTI-layout folder as a user has one, made from the real KITTI 07
// keyframes (skipped when ../shared/data/real is absent): velodyne/NNNNNN.bin as x,y,z,intensity
// (keyframe 2 holds a multiple of 3 points, so its size fits x,y,z too), camera-0 poses in
// poses.txt with a calib.txt, and one pose whose scan is missing. The map is built by
// build_map --kitti-calib from the same folder; the benchmark must skip the missing scan,
// read the calibration with build_map's meaning (else its truth and the map disagree and the
// matches fail), take the tracking offsets given, count every global search (windows with the
// vehicle and without it, with the score floor and without) and write its per-run files.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "../../unit/support/temp_dir.h"
#include "gmm_localization/core/mapping/kitti_source.h"

#ifndef GMM_BUILD_MAP_BINARY
#error "GMM_BUILD_MAP_BINARY (the path of the build_map executable) must be defined"
#endif
#ifndef GMM_BENCH_BINARY
#error "GMM_BENCH_BINARY (the path of the bench_registration executable) must be defined"
#endif

using namespace gmm_localization;
using gmm_localization::testing::TempDir;

namespace {

namespace fs = std::filesystem;

// A KITTI-like velodyne -> camera 0 transform.
const double kTr[12] = {-1.857739385241e-03, -9.999659513510e-01, -8.039975204516e-03,
                        -4.784029760483e-03, -6.481465826011e-03, 8.051860151134e-03,
                        -9.999466081774e-01, -7.337429464231e-02, 9.999773098287e-01,
                        -1.805528627661e-03, -6.496203536139e-03, -3.339968064433e-01};

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

int run(const std::string& command, const std::string& log) {
  const int status = std::system((command + " >" + log + " 2>" + log + ".err").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// The fields of one CSV line (quoted fields may hold commas).
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

/// The CSV's rows (header excluded) as fields.
std::vector<std::vector<std::string>> csvRows(const std::string& csv) {
  std::istringstream in(csv);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) rows.push_back(fields(line));
  return rows;
}

}  // namespace

TEST(BenchRegistration, RunsOnAKittiLayoutFolderWithAMissingScanAndACalibration) {
  const std::string keyframes = std::string(GMM_SHARED_DATA_DIR) + "/real/kitti07_keyframes";
  if (!fs::exists(keyframes + "/graph.txt")) {
    GTEST_SKIP() << "real data absent: " << keyframes << " (see ../shared/data/real/README.md)";
  }
  auto graph = readKittiPoses(keyframes + "/graph.txt");
  ASSERT_TRUE(graph.ok()) << graph.error();
  ASSERT_EQ(graph->size(), 5u);

  TempDir d("bench_registration_test");
  const std::string seq = d.path + "/sequence";
  fs::create_directories(seq + "/velodyne");
  // calib.txt and camera-0 poses: pose_i = Tr * velodyne_i * Tr^-1 (KITTI's convention).
  Eigen::Matrix<double, 3, 4, Eigen::RowMajor> rows34(kTr);
  Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
  tr.matrix().topRows<3>() = rows34;
  tr.linear() = Eigen::Quaterniond(tr.linear()).normalized().toRotationMatrix();
  {
    std::ofstream calib(seq + "/calib.txt");
    calib << "P0: 7.1e+02 0 6.0e+02 0 0 7.1e+02 1.8e+02 0 0 0 1 0\nTr:";
    calib.precision(17);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) calib << ' ' << tr.matrix()(r, c);
    calib << "\n";
    std::ofstream poses(seq + "/poses.txt");
    poses.precision(17);
    for (const auto& [id, velodyne] : graph.value()) {
      const Eigen::Isometry3d cam = tr * velodyne * tr.inverse();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) poses << (r || c ? " " : "") << cam.matrix()(r, c);
      poses << "\n";
    }
  }
  // velodyne/*.bin as xyzi, except keyframe 3 (its pose stays in poses.txt).
  for (int id : {0, 1, 2, 4}) {
    auto pts =
        readKittiScan(keyframes + "/" + std::string(5, '0') + std::to_string(id) + "/points.bin",
                      KittiFields::kXyz);
    ASSERT_TRUE(pts.ok()) << pts.error();
    if (id == 2) {
      ASSERT_EQ(pts->size() % 3, 0u);  // 16-byte records that fit 12 bytes too
    }
    char name[32];
    std::snprintf(name, sizeof name, "/velodyne/%06d.bin", id);
    std::ofstream f(seq + name, std::ios::binary);
    for (const Eigen::Vector3f& p : pts.value()) {
      const float rec[4] = {p.x(), p.y(), p.z(), 0.3f};
      f.write(reinterpret_cast<const char*>(rec), sizeof rec);  // little-endian hosts
    }
  }

  const std::string map = d.path + "/map", out = d.path + "/out", log = d.path + "/log";
  ASSERT_EQ(run(std::string(GMM_BUILD_MAP_BINARY) + " --kitti " + seq + " --kitti-calib " + seq +
                    "/calib.txt --output " + map,
                d.path + "/build_log"),
            0)
      << slurp(d.path + "/build_log.err");
  const std::string bench = std::string(GMM_BENCH_BINARY) + " --map " + map + " --scans " + seq +
                            " --mapping " + seq + " --kitti-calib " + seq +
                            "/calib.txt --count 0 --peer-count 4 --peer-target-stride 1"
                            " --peer-target-exclude 0 --exhaustive-every 0 --no-sizes"
                            " --global-count 2 --global-regions 10 --global-budget 20000"
                            " --track-offset-m 1 --track-offset-deg 2 --threads 2"
                            " --out " +
                            out;
  ASSERT_EQ(run(bench, log), 0) << slurp(log + ".err");
  const std::string stdout_text = slurp(log);
  EXPECT_NE(stdout_text.find("5 poses in " + seq +
                             "/poses.txt, 4 with a scan file, 1 skipped "
                             "(no scan file; first: 3)"),
            std::string::npos)
      << stdout_text;
  EXPECT_NE(stdout_text.find("x,y,z,intensity"), std::string::npos);
  EXPECT_NE(stdout_text.find("tracking: +-2 m, +-3 deg (offsets within 1 m, 2 deg)"),
            std::string::npos);
  EXPECT_NE(stdout_text.find("except the test scan itself"), std::string::npos);
  // The threads table: every scan matched on 1 and 2 threads, the same results.
  EXPECT_NE(stdout_text.find("## Threads: the whole match on 1 and 2 threads"), std::string::npos);
  EXPECT_NE(stdout_text.find("This machine's own ceiling now"), std::string::npos);

  // The per-run files: the report as printed, one CSV row per registration, the JSON summary.
  EXPECT_EQ(slurp(out + "/summary.md"), stdout_text);
  const std::string csv = slurp(out + "/scans.csv");
  ASSERT_EQ(csv.rfind("section,window,matcher,scan,", 0), 0u) << csv;
  // Per matcher: ours in each window on the 4 scans that exist, the peers from the paper
  // window's offsets and from the tracking window's. The scans are in the map: every match of ours
  // succeeds when truth and map share the frame (columns: section 0, window 1, matcher 2, scan 3,
  // success 11).
  std::map<std::string, int> count, ok;
  std::set<std::string> scan_ids;
  double largest_track_offset = 0.0;
  for (const auto& f : csvRows(csv)) {
    ASSERT_EQ(f.size(), 23u) << csv;
    if (f[0] == "window" && f[2] == "gmm_localization" && f[8] == "1") {
      for (size_t k = 19; k < 23; ++k) {  // refine, covariance, certificate, obstacles [ms]
        ASSERT_FALSE(f[k].empty()) << "column " << k << ": " << csv;
        EXPECT_GE(std::stod(f[k]), 0.0) << "column " << k;
      }
    }
    const std::string key = f[0] + " / " + f[1].substr(0, f[1].find(':')) + " / " + f[2];
    ++count[key];
    ok[key] += f[11] == "1";
    scan_ids.insert(f[3]);
    if (key == "window / tracking / gmm_localization") {  // offsets within 1 m and 2 deg
      EXPECT_LE(std::stod(f[6]), 1.0 + 1e-6) << f[6];
      EXPECT_LE(std::stod(f[7]), 2.0 + 1e-6) << f[7];
      largest_track_offset = std::max(largest_track_offset, std::stod(f[6]));
    }
  }
  EXPECT_GT(largest_track_offset, 0.5);
  EXPECT_EQ(scan_ids, (std::set<std::string>{"0", "1", "2", "4"}));
  EXPECT_EQ(count["window / paper / gmm_localization"], 4) << csv;
  EXPECT_EQ(count["window / tracking / gmm_localization"], 4);
  EXPECT_EQ(count["peers / paper / PCL NDT"], 4);
  EXPECT_EQ(count["peers / paper / PCL GICP"], 4);
  EXPECT_EQ(count["peers / tracking / PCL NDT"], 4);
  EXPECT_EQ(count["peers / tracking / PCL GICP"], 4);
  EXPECT_EQ(ok["window / paper / gmm_localization"], 4) << csv;
  EXPECT_EQ(ok["window / tracking / gmm_localization"], 4) << csv;
  // The global rows (a 10 m square, the map as loaded and 100 m wider) on the first two scans,
  // and the same square centred 10 m from the vehicle with the score floor and without it:
  // every search counted in one of its three outcomes.
  EXPECT_EQ(count["global / 10 m x 10 m x 360 deg / gmm_localization"], 2) << csv;
  EXPECT_EQ(count["global / 10 m x 10 m x 360 deg (map radius +100 m) / gmm_localization"], 2);
  EXPECT_EQ(count["global miss / floor -4.50 / gmm_localization"], 2) << csv;
  EXPECT_EQ(count["global miss / floor off / gmm_localization"], 2) << csv;
  EXPECT_NE(stdout_text.find("## Global search where the vehicle is not (10 m x 10 m x 360 deg, "
                             "centre 10 m from it, budget 20000 node scores)"),
            std::string::npos)
      << stdout_text;
  EXPECT_NE(stdout_text.find("| -4.50 | 2 | "), std::string::npos) << stdout_text;
  EXPECT_NE(stdout_text.find("| off | 2 | 0 | "), std::string::npos) << stdout_text;
  const std::string json = slurp(out + "/summary.json");
  EXPECT_NE(json.find("\"skipped_without_file\": 1"), std::string::npos) << json;
  EXPECT_NE(json.find("\"skipped\": [3]"), std::string::npos);
  EXPECT_NE(json.find("\"offset_m\": 1,"), std::string::npos);
  EXPECT_NE(json.find("\"identical_results\": 4, \"compared\": 4"), std::string::npos) << json;
  EXPECT_NE(json.find("{\"region_m\": 10, \"score_floor_per_point\": -4.5, \"budget\": 20000, "
                      "\"scans\": 2,"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("{\"region_m\": 10, \"score_floor_per_point\": null,"), std::string::npos);
}
