// kitti_check: real-data checks on a KITTI-style keyframe dump (../shared/data/real/
// kitti07_keyframes) or a KITTI odometry sequence (velodyne/ scans, poses, calib.txt): what the
// Gaussian mixtures look like on real ground, walls and vegetation
// (`cells`), and leave-one-out registration from random offsets by our search and by PCL NDT
// and GICP (`register`). Prints markdown tables; see docs/real_data.md.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>

#include "common/cli_args.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/mapping/kitti_source.h"
#include "kitti_check/kitti_check_cells.h"
#include "kitti_check/kitti_check_register.h"
#include "kitti_check/kitti_check_report.h"

using namespace gmm_localization;
using namespace gmm_localization::kitti_check;

namespace {

constexpr double kExampleRadiusM = 30.0;  // example cells come from near the keyframes

void usage(FILE* out = stderr) {
  std::fprintf(
      out,
      "kitti_check cells|register --data DIR --work DIR [options]\n"
      "  --data DIR        keyframes, in a layout build_map --kitti takes:\n"
      "                    DIR/NNNNNN/points.bin (keyframe dumps: float32 x,y,z) or\n"
      "                    DIR/velodyne/NNNNNN.bin (KITTI: float32 x,y,z,intensity) or\n"
      "                    DIR/NNNNNN.bin (layout from the file sizes), sensor frame; poses\n"
      "                    DIR/graph.txt ('vN x y z qx qy qz qw' sensor poses), else\n"
      "                    DIR/poses.txt (KITTI 3x4 rows); poses without a scan are skipped\n"
      "  --work DIR        maps and CSV files are written here (created)\n"
      "  --point-format F  auto | xyz | xyzi: force the record layout (auto: as above; a size\n"
      "                    that fits both is read as xyzi with a warning; the choice is printed)\n"
      "  --poses FILE      the poses instead (e.g. KITTI's dataset/poses/07.txt)\n"
      "  --kitti-calib FILE  KITTI odometry calib.txt: the poses are camera-0 poses; map frame =\n"
      "                    first Velodyne frame (z up), as build_map --kitti-calib\n"
      "cells: map from every keyframe (WORK/map_all), each cell with data classed ground / wall /\n"
      "  vegetation / other / below ground from its points (kitti_check_cells.h); prints the\n"
      "  mixtures per class; writes\n"
      "  WORK/cells.csv, WORK/examples.csv and WORK/cloud.bin (float32 x,y,z,class, map frame).\n"
      "register: for each keyframe, a map from the others (WORK/loo_N) and registrations of it\n"
      "  from seeded random offsets, ours and PCL NDT / GICP from the same offsets; writes\n"
      "  WORK/trials.csv.\n"
      "  --offsets N       offsets per keyframe and window (100)\n"
      "  --seed N          offset seed (1)\n"
      "  --keyframes LIST  held-out keyframes, e.g. 0,2-4 (all)\n"
      "  --no-peers        ours only\n"
      "  --no-ours         the peers only\n"
      "  --ndt-resolution M, --ndt-step M, --peer-epsilon E, --peer-iterations N,\n"
      "  --peer-voxel M    peer options (default: the registration benchmark's, bench_peers.h)\n"
      "  --heading-step-deg D  search heading step (registration default 0.5)\n"
      "  --refine-points N points the hill climb scores (registration default 3000; the\n"
      "                    matcher's config/matcher.yaml 1500)\n"
      "  --map-blur-sigma M  the maps' blur kernel sigma (build_map default 0.1; 0: no blur)\n"
      "  --grid-shift M    shift the maps' cell grid by M in x and y (0): the errors that move\n"
      "                    with it come from where structure falls in the 0.2 m cells\n"
      "  --global-region M also a global window: M x M m and the full turn, offsets within\n"
      "                    0.45 M and any heading (0: not; global_search.h)\n"
      "  --global-budget N node scores the global search may compute (200000; 0: unbounded)\n"
      "  --global-points N its search points (200)\n"
      "  --z-period N      the rasters' z coarsening period (2; 0: none, tighter bounds, twice\n"
      "                    the memory)\n"
      "  --threads N       threads of a match, the global search's queues included (1; 0: one\n"
      "                    per hardware thread)\n");
}

struct Args {
  std::string mode, work;
  double global_region_m = 0.0;
  KittiInput data;
  LooOptions loo;
};

bool parse(int argc, char** argv, Args& a) {
  if (argc < 2) return false;
  a.mode = argv[1];
  if (a.mode != "cells" && a.mode != "register") return false;
  for (int i = 2; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--no-peers" || k == "--no-ours") {
      (k == "--no-peers" ? a.loo.peers : a.loo.ours) = false;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "option %s needs a value\n", k.c_str());
      return false;
    }
    const std::string v = argv[++i];
    if (k == "--data") {
      a.data.dir = v;
    } else if (k == "--poses") {
      a.data.poses_file = v;
    } else if (k == "--kitti-calib") {
      a.data.calib_file = v;
    } else if (k == "--point-format") {
      auto f = bench::parsePointFormat(v);
      if (!f.ok()) {
        std::fprintf(stderr, "--point-format: %s\n", f.error().c_str());
        return false;
      }
      a.data.fields = f.value();
    } else if (k == "--work") {
      a.work = v;
    } else if (k == "--offsets") {
      a.loo.offsets = std::atoi(v.c_str());
    } else if (k == "--seed") {
      a.loo.seed = static_cast<uint32_t>(std::atoi(v.c_str()));
    } else if (k == "--heading-step-deg") {
      a.loo.registration.heading_step_rad = std::atof(v.c_str()) * M_PI / 180.0;
    } else if (k == "--refine-points") {
      a.loo.registration.refine_max_points = static_cast<size_t>(std::max(0, std::atoi(v.c_str())));
    } else if (k == "--global-region") {
      a.global_region_m = std::atof(v.c_str());
      if (!(a.global_region_m >= 0.0 && a.global_region_m <= 400.0)) {
        std::fprintf(stderr, "--global-region must be in [0, 400] m\n");
        return false;
      }
    } else if (k == "--global-budget") {
      a.loo.registration.global.max_evaluations = std::atoll(v.c_str());
    } else if (k == "--global-points") {
      a.loo.registration.global.max_points = static_cast<size_t>(std::max(0, std::atoi(v.c_str())));
    } else if (k == "--z-period") {
      a.loo.raster.z_coarsening_period = std::atoi(v.c_str());
    } else if (k == "--threads") {
      a.loo.registration.threads = std::atoi(v.c_str());
      if (a.loo.registration.threads < 0) {
        std::fprintf(stderr, "--threads must be >= 0\n");
        return false;
      }
    } else if (k == "--map-blur-sigma") {
      a.loo.map_blur_sigma_m = std::atof(v.c_str());
    } else if (k == "--grid-shift") {
      a.loo.grid_shift_m = std::atof(v.c_str());
    } else if (k == "--ndt-resolution") {
      a.loo.peer.ndt_resolution_m = std::atof(v.c_str());
    } else if (k == "--ndt-step") {
      a.loo.peer.ndt_step_size_m = std::atof(v.c_str());
    } else if (k == "--peer-epsilon") {
      a.loo.peer.epsilon = std::atof(v.c_str());
    } else if (k == "--peer-iterations") {
      a.loo.peer.max_iterations = std::atoi(v.c_str());
    } else if (k == "--peer-voxel") {
      a.loo.peer.source_voxel_m = std::atof(v.c_str());
      a.loo.peer_target_voxel_m = std::atof(v.c_str());
    } else if (k == "--keyframes") {
      auto list = parseIndexList(v);
      if (!list.ok()) {
        std::fprintf(stderr, "--keyframes: %s\n", list.error().c_str());
        return false;
      }
      a.loo.held_out = list.value();
    } else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return false;
    }
  }
  if (a.data.dir.empty() || a.work.empty()) {
    std::fprintf(stderr, "--data and --work are required\n");
    return false;
  }
  const std::string bad = a.loo.registration.validate();
  if (!bad.empty()) {
    std::fprintf(stderr, "registration options: %s\n", bad.c_str());
    return false;
  }
  const std::string bad_raster = a.loo.raster.validate();
  if (!bad_raster.empty()) {
    std::fprintf(stderr, "raster options: %s\n", bad_raster.c_str());
    return false;
  }
  return true;
}

std::string today() {
  char date[32];
  const std::time_t t = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d", std::localtime(&t));
  return date;
}

int runCells(const Args& a) {
  auto set = loadKeyframes(a.data);
  if (!set.ok()) {
    std::fprintf(stderr, "%s\n", set.error().c_str());
    return 1;
  }
  const std::vector<Keyframe>& keyframes = set->keyframes;
  noteData(set->data, stderr);
  const std::string data_line = describeData(set->data);
  const std::string map_dir = a.work + "/map_all";
  auto built = buildMap(set->data, {}, defaultMapOptions(map_dir));
  if (!built.ok()) {
    std::fprintf(stderr, "%s\n", built.error().c_str());
    return 1;
  }
  auto store = MapStore::open(map_dir);
  auto map = store.ok() ? store->loadAll() : Result<GmmMap>::failure(store.error());
  if (!map.ok()) {
    std::fprintf(stderr, "%s\n", map.error().c_str());
    return 1;
  }
  const PointList cloud = worldCloud(keyframes, {}, 0.0);
  const PointLabels labels = classifyPoints(cloud, ClassifierOptions());
  const std::vector<CellRecord> cells = classifyCells(map.value(), cloud, labels);
  const MapBuildStats& s = built.value();
  const uint64_t with_data = s.cells_by_components[1] + s.cells_by_components[2];
  std::printf("# Gaussian mixtures on real ground, walls and vegetation, %s\n\n", today().c_str());
  std::printf(
      "map %s from %zu keyframes of %s (%llu points; 0.2 m cells, K <= 2, build_map defaults): "
      "%llu cells with data, %.1f%% with 1 component, %.1f%% with 2\n\n",
      map_dir.c_str(), keyframes.size(), a.data.dir.c_str(),
      static_cast<unsigned long long>(s.kept_points), static_cast<unsigned long long>(with_data),
      100.0 * s.cells_by_components[1] / std::max<uint64_t>(1, with_data),
      100.0 * s.cells_by_components[2] / std::max<uint64_t>(1, with_data));
  std::printf("%s\n\n", data_line.c_str());
  std::vector<Eigen::Vector2d> centres;
  for (const Keyframe& k : keyframes) centres.push_back(k.truth.translation().head<2>());
  const std::vector<size_t> examples = exampleCells(cells, centres, kExampleRadiusM);
  printCellTables(cells, examples, stdout);
  if (!writeCellsCsv(cells, examples, a.work + "/cells.csv", a.work + "/examples.csv")) {
    std::fprintf(stderr, "cannot write the CSV files in %s\n", a.work.c_str());
    return 1;
  }
  std::FILE* f = std::fopen((a.work + "/cloud.bin").c_str(), "wb");
  if (f == nullptr) return 1;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float rec[4] = {cloud[i].x(), cloud[i].y(), cloud[i].z(),
                          static_cast<float>(static_cast<int>(labels.labels[i]))};
    std::fwrite(rec, sizeof(rec), 1, f);
  }
  return std::fclose(f) == 0 ? 0 : 1;
}

int runRegister(Args a) {
  a.loo.data = a.data;
  a.loo.work_dir = a.work;
  if (a.global_region_m > 0.0) {
    a.loo.windows = defaultWindows();
    WindowSpec g;
    g.name = "global " + std::to_string(static_cast<int>(std::lround(a.global_region_m))) +
             " m x " + std::to_string(static_cast<int>(std::lround(a.global_region_m))) +
             " m, 360 deg";
    g.half_m = a.global_region_m / 2.0;
    g.half_deg = 180.0;
    g.offset_m = 0.45 * a.global_region_m;
    g.offset_deg = 180.0;
    a.loo.windows.push_back(g);
  }
  auto report = runLeaveOneOut(a.loo);
  if (!report.ok()) {
    std::fprintf(stderr, "%s\n", report.error().c_str());
    return 1;
  }
  std::printf("# Leave-one-out registration of %s, %s, one thread\n\n", a.data.dir.c_str(),
              today().c_str());
  std::printf("%s\n\n", describeData(report->data).c_str());
  std::printf(
      "%d seeded offsets (seed %u) per keyframe and window; priors keep the SLAM pose's z, roll "
      "and pitch (gravity from an IMU); errors against the SLAM poses; success: < 0.5 m and < 1 "
      "deg. Peers: PCL NDT and GICP (src/tools/bench/bench_peers.cpp) on the other keyframes' "
      "points (voxel %.2f m), started at the same offset poses; scan voxel %.2f m, NDT "
      "resolution %.2f m, NDT step %.2f m, epsilon %g, at most %d iterations, GICP "
      "correspondences within %.1f m.\n\n",
      a.loo.offsets, a.loo.seed, a.loo.peer_target_voxel_m, a.loo.peer.source_voxel_m,
      a.loo.peer.ndt_resolution_m, a.loo.peer.ndt_step_size_m, a.loo.peer.epsilon,
      a.loo.peer.max_iterations, a.loo.peer.gicp_max_correspondence_m);
  printLooTables(report.value(), stdout);
  if (!writeTrialsCsv(report.value(), a.work + "/trials.csv")) {
    std::fprintf(stderr, "cannot write %s/trials.csv\n", a.work.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  gmm_localization::tools::NormalizedArgs args(argc, argv);
  for (int i = 1; i < args.argc(); ++i) {
    const std::string w = args.argv()[i];
    if (w == "--help" || w == "-h") {
      usage(stdout);
      return gmm_localization::tools::kExitOk;
    }
  }
  if (!parse(args.argc(), args.argv(), a)) {
    usage();
    return 2;
  }
  std::error_code ec;
  std::filesystem::create_directories(a.work, ec);
  if (ec) {
    std::fprintf(stderr, "cannot create %s: %s\n", a.work.c_str(), ec.message().c_str());
    return 1;
  }
  return a.mode == "cells" ? runCells(a) : runRegister(a);
}
