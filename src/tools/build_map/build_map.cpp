// build_map: builds a Gaussian mixture map from a PCD map, KITTI-style scans, a rosbag or a
// synthetic street (see --help), with a progress bar and a final summary.
#include <sys/resource.h>
#include <time.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>

#include "build_map/build_map_options.h"
#include "build_map/build_map_readers.h"
#include "build_map/build_map_synthetic.h"
#include "common/cli_args.h"
#include "common/progress_bar.h"
#include "gmm_localization/core/mapping/map_builder.h"

using namespace gmm_localization;
using namespace gmm_localization::tools;

namespace {

Result<std::unique_ptr<PointBatchSource>> openSource(const BuildMapConfig& c) {
  using R = Result<std::unique_ptr<PointBatchSource>>;
  Eigen::Isometry3d map_T_world = Eigen::Isometry3d::Identity();
  map_T_world.translation() = -c.offset_m;
  switch (c.input) {
    case InputKind::kPcd: {
      PcdSourceOptions p;
      p.paths = c.pcd_paths;
      p.batch_points = c.pcd_batch_points;
      p.world_T_file = c.pcd_world_T_file;
      p.offset_m = c.offset_m;
      p.max_abs_z_m = c.pcd_max_abs_z_m;
      auto s = PcdSource::open(p);
      if (!s) return R::failure(s.error());
      return R(std::unique_ptr<PointBatchSource>(std::move(*s)));
    }
    case InputKind::kKitti: {
      KittiSourceOptions k = c.kitti;
      k.map_T_world = map_T_world;
      if (!c.kitti_calib.empty()) {
        auto tr = readKittiCalibTr(c.kitti_calib);
        if (!tr) return R::failure(tr.error());
        k.pose_T_sensor = *tr;
        k.map_T_world = map_T_world * tr->inverse();
      }
      auto s = KittiScanSource::open(k);
      if (!s) return R::failure(s.error());
      return R(std::unique_ptr<PointBatchSource>(std::move(*s)));
    }
    case InputKind::kBag: {
      RosbagSourceOptions b;
      b.path = c.bag.path;
      b.cloud_topic = c.bag.cloud_topic;
      b.pose_topic = c.bag.pose_topic;
      b.pose_tf_parent = c.bag.pose_tf_parent;
      b.pose_tf_child = c.bag.pose_tf_child;
      b.has_extrinsic = c.bag.has_extrinsic;
      b.pose_T_cloud = c.bag.pose_T_cloud;
      b.map_T_world = map_T_world;
      b.max_pose_gap_s = c.bag.max_pose_gap_s;
      b.every = c.bag.every;
      b.deskew = c.bag.deskew;
      b.time_field = c.bag.time_field;
      auto s = RosbagSource::open(b);
      if (!s) return R::failure(s.error());
      return R(std::unique_ptr<PointBatchSource>(std::move(*s)));
    }
    case InputKind::kSynthetic:
      return R(std::unique_ptr<PointBatchSource>(new SyntheticStreetSource(c.synthetic)));
    case InputKind::kNone:
      break;
  }
  return R::failure("no input");
}

double threadCpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double processCpuSeconds() {
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Prints the source's new warnings (PCD input), each on its own line.
void printWarnings(PointBatchSource& src) {
  auto* pcd = dynamic_cast<PcdSource*>(&src);
  if (!pcd) return;
  for (const std::string& w : pcd->takeWarnings()) std::cerr << "build_map: warning: " << w << "\n";
}

std::string mb(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f MB", bytes / 1e6);
  return buf;
}

std::string pct(uint64_t part, uint64_t whole) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f%%", whole ? 100.0 * part / whole : 0.0);
  return buf;
}

}  // namespace

int run(int argc, char** argv) {
  auto config = parseBuildMapArgs(argc, argv);
  if (!config) {
    std::cerr << "build_map: " << config.error() << "\n";
    return 2;
  }
  if (config->help) {
    std::cout << buildMapHelp();
    return 0;
  }
  BuildMapConfig& c = *config;
  auto source = openSource(c);
  if (!source) {
    std::cerr << "build_map: " << source.error() << "\n";
    return 1;
  }
  PointBatchSource& src = **source;
  printWarnings(src);
  c.builder.provenance = "build_map from " + src.describe();
  auto builder = MapBuilder::create(c.builder);
  if (!builder) {
    std::cerr << "build_map: " << builder.error() << "\n";
    return 1;
  }
  MapBuilder& b = **builder;

  // Pass 1: read and bin. Time inside the source (file reading, decoding or generating) is
  // kept apart from the builder's own time, so the throughput is the builder's.
  using Clock = std::chrono::steady_clock;
  double source_s = 0.0, bin_s = 0.0, bin_cpu_s = 0.0;
  ProgressBar read_bar("reading", !c.quiet);
  const size_t total = src.sizeHint();
  PointBatch batch;
  for (size_t done = 0;;) {
    const auto t0 = Clock::now();
    auto more = src.next(batch);
    const auto t1 = Clock::now();
    source_s += std::chrono::duration<double>(t1 - t0).count();
    if (!more) {
      std::cerr << "\n";
      printWarnings(src);
      std::cerr << "build_map: " << more.error() << "\n";
      return 1;
    }
    if (!*more) break;
    // What the layer needs (the reflectivity layer: intensities, a vehicle pose), checked here
    // so that the reason names the input.
    const std::string lacking = b.options().batchError(batch);
    if (!lacking.empty()) {
      std::cerr << "\nbuild_map: " << src.describe() << ": batch " << done + 1 << ": " << lacking
                << "\n";
      return 1;
    }
    const double c1 = threadCpuSeconds();
    Status s = b.addBatch(batch);
    bin_cpu_s += threadCpuSeconds() - c1;
    bin_s += std::chrono::duration<double>(Clock::now() - t1).count();
    if (!s) {
      std::cerr << "\nbuild_map: " << s.error() << "\n";
      return 1;
    }
    ++done;
    read_bar.update(total ? static_cast<double>(done) / total : 0.0,
                    std::to_string(done) + (total ? "/" + std::to_string(total) : "") +
                        " batches, " + withCommas(b.stats().input_points) + " points");
  }
  read_bar.finish(withCommas(b.stats().input_points) + " points, " +
                  withCommas(b.stats().kept_points) + " kept");
  printWarnings(src);

  // Pass 2: fit and write.
  ProgressBar fit_bar("fitting", !c.quiet);
  const auto f0 = Clock::now();
  const double fit_cpu0 = processCpuSeconds();
  auto stats = b.finish([&](const BuildProgress& p) {
    if (p.stage == BuildProgress::Stage::kFitting) {
      fit_bar.update(p.work_total ? static_cast<double>(p.work_done) / p.work_total : 0.0,
                     std::to_string(p.tiles_done) + "/" + std::to_string(p.tiles_total) + " tiles");
    }
    return true;
  });
  const double fit_s = std::chrono::duration<double>(Clock::now() - f0).count();
  const double fit_cpu_s = processCpuSeconds() - fit_cpu0;
  if (!stats) {
    std::cerr << "\nbuild_map: " << stats.error() << "\n";
    return 1;
  }
  fit_bar.finish(std::to_string(stats->tiles) + " tiles");

  const MapBuildStats& s = *stats;
  const uint64_t cells = s.cells_by_components[0] + s.cells_by_components[1] +
                         s.cells_by_components[2] + s.cells_by_components[3];
  const uint64_t non_empty = cells - s.cells_by_components[0];
  std::printf("build_map summary\n");
  std::printf("  input            %s\n", src.describe().c_str());
  if (auto* bag = dynamic_cast<RosbagSource*>(&src))
    std::printf("  skipped scans    %s\n", bag->skipped().c_str());
  if (auto* pcd = dynamic_cast<PcdSource*>(&src))
    std::printf("  dropped on read  %s\n", pcd->dropped().c_str());
  std::printf("  output           %s\n", c.builder.output_directory.c_str());
  std::printf("  options          %s\n", c.builder.describe().c_str());
  // The reflectivity layer keeps the ground returns only: their definition and counts.
  const bool reflectivity = c.builder.layer == MapLayer::kReflectivity;
  const std::string layer_definition =
      reflectivity ? " (" + describeReflectivityLayer(c.builder.reflectivity) + ")" : "";
  const std::string not_ground =
      reflectivity ? withCommas(s.dropped_not_ground) + " not ground, " : "";
  std::printf("  layer            %s%s\n", mapLayerName(c.builder.layer), layer_definition.c_str());
  std::printf(
      "  input points     %s in %s batches (%s without sensor origin: not range-filtered)\n",
      withCommas(s.input_points).c_str(), withCommas(s.batches).c_str(),
      withCommas(s.batches_without_origin).c_str());
  std::printf(
      "  points kept      %s (%s)%s; dropped: %s invalid, %s range, %s height, %s%s voxel\n",
      withCommas(s.kept_points).c_str(), pct(s.kept_points, s.input_points).c_str(),
      reflectivity ? " as ground returns" : "", withCommas(s.dropped_invalid).c_str(),
      withCommas(s.dropped_range).c_str(), withCommas(s.dropped_height).c_str(), not_ground.c_str(),
      withCommas(s.dropped_voxel).c_str());
  std::printf("  cells            %s in tiles; %s with data\n", withCommas(cells).c_str(),
              withCommas(non_empty).c_str());
  for (int k = 0; k <= kMaxMixtureComponents; ++k) {
    if (k > c.builder.em.max_components && s.cells_by_components[k] == 0) continue;
    std::printf("    %d component%s  %12s  (%s of cells with data)\n", k, k == 1 ? " " : "s",
                withCommas(s.cells_by_components[k]).c_str(),
                k == 0 ? "-" : pct(s.cells_by_components[k], non_empty).c_str());
  }
  std::printf("  tiles            %s of %d x %d cells (%.1f m)\n", withCommas(s.tiles).c_str(),
              c.builder.geometry.tile_size_cells, c.builder.geometry.tile_size_cells,
              c.builder.geometry.tileSizeM());
  std::printf("  on disk          %s (%.2f B per cell with data; spill files used %s)\n",
              mb(s.map_bytes).c_str(), non_empty ? s.map_bytes * 1.0 / non_empty : 0.0,
              mb(s.spill_bytes).c_str());
  if (c.input == InputKind::kSynthetic) {
    std::printf("  size per km      %.2f MB/km of street\n",
                s.map_bytes / 1e6 / (c.synthetic.length_m / 1000.0));
  }
  if (s.em.fits > 0) {
    std::printf(
        "  EM               %s cell fits, %.1f samples per fit, %.2f EM runs (K >= 2) per fit, "
        "%.1f iterations per run\n",
        withCommas(s.em.fits).c_str(), 1.0 * s.em.samples / s.em.fits,
        1.0 * s.em.em_runs / s.em.fits, s.em.em_runs ? 1.0 * s.em.iterations / s.em.em_runs : 0.0);
  }
  const double build_s = bin_s + fit_s;
  const double build_cpu_s = bin_cpu_s + fit_cpu_s;
  std::printf(
      "  time (wall)      input %.1f s, binning %.1f s, fitting+writing %.1f s (%d threads)\n",
      source_s, bin_s, fit_s, c.builder.threads);
  std::printf("  time (CPU)       binning %.1f s, fitting+writing %.1f s\n", bin_cpu_s, fit_cpu_s);
  std::printf(
      "  throughput       %s input points/s wall, %s input points per CPU-second "
      "(builder only: binning + fitting + writing)\n",
      withCommas(static_cast<uint64_t>(build_s > 0 ? s.input_points / build_s : 0)).c_str(),
      withCommas(static_cast<uint64_t>(build_cpu_s > 0 ? s.input_points / build_cpu_s : 0))
          .c_str());
  return 0;
}

int main(int argc, char** argv) {
  // Every reader reports errors as values; this is the last line of defence against a library
  // (rosbag, the standard library) throwing.
  try {
    gmm_localization::tools::NormalizedArgs args(argc, argv);
    return run(args.argc(), args.argv());
  } catch (const std::exception& e) {
    std::cerr << "\nbuild_map: error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "\nbuild_map: error: unknown exception\n";
  }
  return 1;
}
