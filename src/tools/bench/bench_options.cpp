#include "bench/bench_options.h"

#include "bench/bench_methods.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <map>
#include <type_traits>

namespace gmm_localization {
namespace bench {

const char* benchUsage() {
  return "bench_registration --map DIR --scans KITTI_DIR [--mapping KITTI_DIR] [options]\n"
         "Data (KITTI-style folders, the layouts build_map --kitti takes):\n"
         "  --map DIR            Gaussian mixture map (build_map output)\n"
         "  --scans DIR          test scans with ground-truth poses: DIR/velodyne/NNNNNN.bin\n"
         "                       (a KITTI odometry sequence, simulate --kitti), DIR/NNNNNN.bin or\n"
         "                       DIR/NNNNNN/points.bin; poses DIR/graph.txt, else DIR/poses.txt.\n"
         "                       Poses without a scan file are skipped (the count is printed)\n"
         "  --poses FILE         the test scans' poses instead (KITTI 3x4 rows, line i = scan i,\n"
         "                       e.g. dataset/poses/07.txt, or 'id x y z qx qy qz qw' lines)\n"
         "  --kitti-calib FILE   KITTI odometry calib.txt: the poses are camera-0 poses; map "
         "frame\n"
         "                       = first Velodyne frame (z up), as build_map --kitti-calib (build\n"
         "                       the map with the same file). Applies to --scans and --mapping\n"
         "  --point-format F     auto | xyz | xyzi records (auto: xyzi under velodyne/, xyz for\n"
         "                       NNNNNN/points.bin, else from the file sizes; the choice is "
         "printed)\n"
         "  --mapping DIR        mapping scans: target clouds for PCL NDT/GICP (optional)\n"
         "  --mapping-poses FILE their poses (default as for --scans)\n"
         "Runs:\n"
         "  --count N            test scans, evenly spread over those with a file (30; 0 = all)\n"
         "  --peer-count N       scans for the NDT/GICP comparison (20; 0 = skip)\n"
         "  --exhaustive-every N check branch-and-bound against exhaustive on every N-th scan (3)\n"
         "  --offset-m M         paper window: offsets uniform in a disc of this radius (10)\n"
         "  --offset-deg D       and within +-D degrees of heading (15)\n"
         "  --track-offset-m M   tracking window (+-2 m, +-3 deg): offsets within M (1.5)\n"
         "  --track-offset-deg D and within +-D degrees (2.5)\n"
         "  --seed N             offset seed (1)\n"
         "  --methods LIST       match methods timed side by side: height, reflectivity, fused,\n"
         "                       comma-separated, or all (height: the paper's, always run, the\n"
         "                       reference). reflectivity and fused read MAP/reflectivity\n"
         "                       (build_map --layer reflectivity) and need x,y,z,intensity\n"
         "                       scans; each scan is matched by each method from the same prior,\n"
         "                       right after its height match: a methods table with the ratios\n"
         "                       to height (height)\n"
         "  --threads N          also run both windows with the match on N threads (0: one per\n"
         "                       hardware thread): a table of the stages' times on 1 and N\n"
         "                       threads, the speed-ups and whether every result is identical (1:\n"
         "                       one thread only)\n"
         "  --out DIR            also write DIR/scans.csv (one row per registration),\n"
         "                       DIR/summary.md (the tables as printed) and DIR/summary.json\n"
         "Peers' target cloud (from --mapping):\n"
         "  --peer-target-stride N   mapping scans whose index is a multiple of N (5: suits the\n"
         "                       simulator's 10 Hz mapping pass and keeps earlier figures\n"
         "                       comparable; 1: every scan)\n"
         "  --peer-target-exclude N  leave out mapping scans whose index is within N of the test\n"
         "                       scan's (0: the scan itself; -1: none, the default). For a real\n"
         "                       sequence used as both --scans and --mapping, e.g.\n"
         "                       --peer-target-stride 1 --peer-target-exclude 0 (build the map\n"
         "                       without the test scans, build_map --scans, to be fair to both)\n"
         "  --peer-target-radius M   points within M of the test scan, from mapping scans within\n"
         "                       M/2 (80)\n"
         "Search:\n"
         "  --heading-step-deg D search heading step (0.5)\n"
         "  --max-points N       search points after voxelling (registration default)\n"
         "  --voxel M            search voxel (registration default)\n"
         "  --ground-share S     largest share of ground points among search points (default)\n"
         "  --z-period N         raster z coarsening period (raster default)\n"
         "  --layers N           raster layers (raster default)\n"
         "  --refine-points N    points the hill climb scores (registration default)\n"
         "Tables:\n"
         "  --global-count N     scans per global-localization row (10; first N of the test "
         "scans)\n"
         "  --global-regions A,B square region edges of the global rows [m] (25,50,100)\n"
         "  --global-points N    search points of the global search (registration default)\n"
         "  --global-budget N    node scores the global search may compute (default: unbounded)\n"
         "  --global-root-headings L  root heading intervals of 2^L headings (default)\n"
         "  --global-split-share S    heading-vs-translation split rule (default)\n"
         "  --global-threads N   threads of the global search (2)\n"
         "  --global-reads N     layer reads per point and node in the interval bound (default)\n"
         "  --global-floor F     score floor of the global search [nats/pt] (registration "
         "default), off: none\n"
         "  --no-global          skip the global-localization table\n"
         "  --no-sizes           skip the scan-size table\n"
         "  --no-memory-floor    skip measuring memory latency and bandwidth (256 MB, about 2 s)\n"
         "                       and the search-against-memory table\n";
}

namespace {

bool toDouble(const char* v, double& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtod(v, &end);
  return end != v && *end == '\0' && errno == 0 && std::isfinite(out);
}

bool toLong(const char* v, long long& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtoll(v, &end, 10);
  return end != v && *end == '\0' && errno == 0;
}

}  // namespace

bool parseBenchOptions(int argc, char** argv, BenchOptions& o, bool& help) {
  help = false;
  std::string point_format = "auto";
  // Each option with a value: its handler, false when the value is not acceptable.
  auto real = [](double& dst, double lo) {
    return [&dst, lo](const char* v) {
      double d;
      if (!toDouble(v, d) || d < lo) return false;
      dst = d;
      return true;
    };
  };
  auto integer = [](auto& dst, long long lo) {
    return [&dst, lo](const char* v) {
      long long n;
      if (!toLong(v, n) || n < lo || n > 2000000000LL) return false;
      dst = static_cast<std::remove_reference_t<decltype(dst)>>(n);
      return true;
    };
  };
  auto text = [](std::string& dst) {
    return [&dst](const char* v) {
      dst = v;
      return true;
    };
  };
  auto degrees = [](double& rad) {
    return [&rad](const char* v) {
      double d;
      if (!toDouble(v, d) || !(d > 0.0)) return false;
      rad = d * M_PI / 180.0;
      return true;
    };
  };
  long long global_budget = o.reg.global.max_evaluations;
  const std::map<std::string, std::function<bool(const char*)>> with_value = {
      {"--map", text(o.map_dir)},
      {"--scans", text(o.scans.dir)},
      {"--poses", text(o.scans.poses_file)},
      {"--kitti-calib", text(o.scans.calib_file)},
      {"--point-format", text(point_format)},
      {"--mapping", text(o.mapping.dir)},
      {"--mapping-poses", text(o.mapping.poses_file)},
      {"--out", text(o.out_dir)},
      {"--count", integer(o.count, 0)},
      {"--peer-count", integer(o.peer_count, 0)},
      {"--exhaustive-every", integer(o.exhaustive_every, 0)},
      {"--offset-m", real(o.offset_m, 0.0)},
      {"--offset-deg", real(o.offset_deg, 0.0)},
      {"--track-offset-m", real(o.track_offset_m, 0.0)},
      {"--track-offset-deg", real(o.track_offset_deg, 0.0)},
      {"--seed", integer(o.seed, 0)},
      {"--methods", [&o](const char* v) { return parseMethodList(v, &o.methods); }},
      {"--threads", integer(o.threads, 0)},
      {"--peer-target-stride", integer(o.peer_target.stride, 1)},
      {"--peer-target-exclude", integer(o.peer_target.exclude, -1)},
      {"--peer-target-radius", real(o.peer_target.radius_m, 1.0)},
      {"--heading-step-deg", degrees(o.reg.heading_step_rad)},
      {"--max-points", integer(o.reg.filter.max_points, 1)},
      {"--voxel", real(o.reg.filter.voxel_m, 0.0)},
      {"--ground-share", real(o.reg.filter.ground_share, 0.0)},
      {"--z-period", integer(o.raster.z_coarsening_period, 0)},
      {"--layers", integer(o.raster.num_layers, 0)},
      {"--refine-points", integer(o.reg.refine_max_points, 1)},
      {"--global-count", integer(o.global_count, 0)},
      {"--global-threads", integer(o.global_threads, 1)},
      {"--global-points", integer(o.reg.global.max_points, 1)},
      {"--global-budget", integer(global_budget, 0)},
      {"--global-root-headings", integer(o.reg.global.root_heading_levels, 0)},
      {"--global-split-share", real(o.reg.global.heading_split_share, 0.0)},
      {"--global-reads", integer(o.reg.global.max_reads_per_point, 1)},
      {"--global-floor",
       [&o](const char* v) {
         double f;
         if (std::string(v) == "off") {
           o.reg.global.min_score_per_point = -std::numeric_limits<double>::infinity();
           return true;
         }
         if (!toDouble(v, f) || !std::isfinite(f)) return false;
         o.reg.global.min_score_per_point = f;
         return true;
       }},
      {"--global-regions",
       [&o](const char* v) {
         o.global_regions_m.clear();
         for (const char* q = v; *q != '\0';) {
           char* end = nullptr;
           const double edge = std::strtod(q, &end);
           if (end == q || !(edge > 0.0)) return false;
           o.global_regions_m.push_back(edge);
           if (*end != ',' && *end != '\0') return false;
           q = *end == ',' ? end + 1 : end;
         }
         return !o.global_regions_m.empty();
       }},
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      help = true;
      return false;
    }
    if (a == "--no-sizes" || a == "--no-global" || a == "--no-memory-floor") {
      (a == "--no-sizes" ? o.sizes : a == "--no-global" ? o.global : o.memory_floor) = false;
      continue;
    }
    const auto handler = with_value.find(a);
    if (handler == with_value.end()) {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return false;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "option %s needs a value\n", a.c_str());
      return false;
    }
    if (!handler->second(argv[++i])) {
      std::fprintf(stderr, "option %s: bad value '%s'\n", a.c_str(), argv[i]);
      return false;
    }
  }
  o.reg.global.max_evaluations = global_budget;
  auto fields = parsePointFormat(point_format);
  if (!fields.ok()) {
    std::fprintf(stderr, "--point-format: %s\n", fields.error().c_str());
    return false;
  }
  o.scans.fields = o.mapping.fields = fields.value();
  o.mapping.calib_file = o.scans.calib_file;
  if (o.map_dir.empty() || o.scans.dir.empty()) {
    std::fprintf(stderr, "--map and --scans are required\n");
    return false;
  }
  if (!o.mapping.poses_file.empty() && o.mapping.dir.empty()) {
    std::fprintf(stderr, "--mapping-poses needs --mapping\n");
    return false;
  }
  return true;
}

}  // namespace bench
}  // namespace gmm_localization
