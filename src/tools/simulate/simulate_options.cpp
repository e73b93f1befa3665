#include "simulate/simulate_options.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <sstream>

#include "simulate/simulate_imperfection_options.h"

namespace gmm_localization {
namespace tools {

namespace {

Result<std::vector<sim::GridNode>> parseRoute(const std::string& v) {
  std::vector<sim::GridNode> nodes;
  std::stringstream ss(v);
  std::string item;
  while (std::getline(ss, item, ';')) {
    sim::GridNode n;
    char comma = 0;
    std::stringstream is(item);
    if (!(is >> n.i >> comma >> n.j) || comma != ',')
      return Result<std::vector<sim::GridNode>>::failure("option --route: '" + item +
                                                         "' is not 'i,j'");
    nodes.push_back(n);
  }
  return nodes;
}

}  // namespace

Result<SimulateOptions> parseSimulateOptions(int argc, char** argv) {
  using R = Result<SimulateOptions>;
  // First pass: the pass type sets the defaults that the other options then override.
  sim::PassType type = sim::PassType::kMapping;
  uint64_t pass_seed = 1;
  for (int k = 1; k + 1 < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--pass") {
      auto t = sim::parsePassType(argv[k + 1]);
      if (!t) return R::failure("option --pass: " + t.error());
      type = *t;
    } else if (a == "--pass-seed") {
      pass_seed = std::strtoull(argv[k + 1], nullptr, 10);
    }
  }
  SimulateOptions o;
  o.config = sim::SimulationConfig::defaults(type, pass_seed);
  sim::SimulationConfig& c = o.config;
  int sensors = 4;
  double mount_height = 1.95, tilt = 5.0, azimuth_step = 0.0;
  ImperfectionFlags imperfection;

  using Setter = std::function<Status(double)>;
  std::map<std::string, Setter> num = {
      {"--town-seed",
       [&](double v) {
         c.town.seed = static_cast<uint64_t>(v);
         return Status::success();
       }},
      {"--town-size",
       [&](double v) {
         c.town.size_x_m = c.town.size_y_m = v;
         return Status::success();
       }},
      {"--town-size-x",
       [&](double v) {
         c.town.size_x_m = v;
         return Status::success();
       }},
      {"--town-size-y",
       [&](double v) {
         c.town.size_y_m = v;
         return Status::success();
       }},
      {"--block-min",
       [&](double v) {
         c.town.block_min_m = v;
         return Status::success();
       }},
      {"--block-max",
       [&](double v) {
         c.town.block_max_m = v;
         return Status::success();
       }},
      {"--building-density",
       [&](double v) {
         c.town.building_density = v;
         return Status::success();
       }},
      {"--tree-spacing",
       [&](double v) {
         c.town.tree_spacing_m = v;
         return Status::success();
       }},
      {"--terrain-slope",
       [&](double v) {
         c.town.terrain_slope_x = v;
         c.town.terrain_slope_y = -0.6 * v;
         return Status::success();
       }},
      {"--route-seed",
       [&](double v) {
         c.route.seed = static_cast<uint64_t>(v);
         return Status::success();
       }},
      {"--route-length",
       [&](double v) {
         c.route.length_m = v;
         return Status::success();
       }},
      {"--pass-seed", [&](double) { return Status::success(); }},
      {"--moving-cars",
       [&](double v) {
         c.pass.moving_cars_per_km2 = v;
         return Status::success();
       }},
      {"--pedestrians",
       [&](double v) {
         c.pass.pedestrians_per_km2 = v;
         return Status::success();
       }},
      {"--parked-keep",
       [&](double v) {
         c.pass.parked_keep_probability = v;
         return Status::success();
       }},
      {"--snowfall",
       [&](double v) {
         c.pass.snowfall_returns_per_ray = v;
         return Status::success();
       }},
      {"--start-offset",
       [&](double v) {
         c.start_offset_m = v;
         return Status::success();
       }},
      {"--distance",
       [&](double v) {
         c.max_distance_m = v;
         return Status::success();
       }},
      {"--duration",
       [&](double v) {
         c.max_duration_s = v;
         return Status::success();
       }},
      {"--sensors",
       [&](double v) {
         sensors = static_cast<int>(v);
         return (sensors == 1 || sensors == 4) ? Status::success()
                                               : Status::failure("option --sensors: 1 or 4");
       }},
      {"--rate",
       [&](double v) {
         c.lidar.rotation_rate_hz = v;
         return Status::success();
       }},
      {"--azimuth-step",
       [&](double v) {
         azimuth_step = v;
         return v > 0.0 ? Status::success() : Status::failure("option --azimuth-step must be > 0");
       }},
      {"--range-noise",
       [&](double v) {
         c.lidar.range_noise_m = v;
         return Status::success();
       }},
      {"--dropout",
       [&](double v) {
         c.lidar.dropout_probability = v;
         return Status::success();
       }},
      {"--max-range",
       [&](double v) {
         c.lidar.max_range_m = v;
         return Status::success();
       }},
      {"--mount-height",
       [&](double v) {
         mount_height = v;
         return Status::success();
       }},
      {"--tilt",
       [&](double v) {
         tilt = v;
         return Status::success();
       }},
      {"--ins-scale-error",
       [&](double v) {
         c.ins.scale_error = v;
         return Status::success();
       }},
      {"--ins-heading-bias",
       [&](double v) {
         c.ins.heading_bias_rad = v * M_PI / 180.0;
         return Status::success();
       }},
      {"--ins-heading-rw",
       [&](double v) {
         c.ins.heading_random_walk_rad_sqrt_s = v * M_PI / 180.0;
         return Status::success();
       }},
      {"--ins-position-noise",
       [&](double v) {
         c.ins.position_noise_m = v;
         return Status::success();
       }},
      {"--imu-gyro-noise",
       [&](double v) {
         c.ins.gyro_noise_rad_s = v;
         return Status::success();
       }},
      {"--imu-accel-noise",
       [&](double v) {
         c.ins.accel_noise_mps2 = v;
         return Status::success();
       }},
      {"--odom-rate",
       [&](double v) {
         c.ins.odom_rate_hz = v;
         return Status::success();
       }},
      {"--imu-rate",
       [&](double v) {
         c.ins.imu_rate_hz = v;
         return Status::success();
       }},
      {"--gt-rate",
       [&](double v) {
         c.ground_truth_rate_hz = v;
         return Status::success();
       }},
      {"--noise-seed",
       [&](double v) {
         c.noise_seed = static_cast<uint64_t>(v);
         return Status::success();
       }},
      {"--epoch",
       [&](double v) {
         o.bag.epoch_s = v;
         return Status::success();
       }},
      {"--kitti-every",
       [&](double v) {
         o.kitti_every = static_cast<int>(v);
         return o.kitti_every >= 1 ? Status::success()
                                   : Status::failure("option --kitti-every must be >= 1");
       }},
      {"--map-drift-per-100m",
       [&](double v) {
         o.map_pose_error.drift_m_per_100m = v;
         return Status::success();
       }},
      {"--map-drift-deg-per-100m",
       [&](double v) {
         o.map_pose_error.drift_deg_per_100m = v;
         return Status::success();
       }},
      {"--map-residual-m",
       [&](double v) {
         o.map_pose_error.residual_m = v;
         return Status::success();
       }},
      {"--map-residual-deg",
       [&](double v) {
         o.map_pose_error.residual_deg = v;
         return Status::success();
       }},
      {"--map-loop-radius",
       [&](double v) {
         o.map_pose_error.loop_radius_m = v;
         return Status::success();
       }},
      {"--map-pose-seed",
       [&](double v) {
         if (v < 0.0) return Status::failure("option --map-pose-seed must be >= 0");
         o.map_pose_error.seed = static_cast<uint64_t>(v);
         return Status::success();
       }},
      {"--threads",
       [&](double v) {
         c.threads = static_cast<int>(v);
         return Status::success();
       }},
  };
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--help" || a == "-h") {
      o.help = true;
      return o;
    }
    if (a == "--lz4") {
      o.bag.lz4 = true;
      continue;
    }
    if (a == "--per-sensor-clouds") {
      o.bag.per_sensor_clouds = true;
      continue;
    }
    if (a == "--no-merged") {
      o.bag.merged_cloud = false;
      continue;
    }
    if (a == "--kitti-labels") {
      o.kitti_labels = true;
      continue;
    }
    if (a == "--quiet") {
      o.quiet = true;
      continue;
    }
    if (a == "--dry-run") {
      o.dry_run = true;
      continue;
    }
    if (k + 1 >= argc)
      return R::failure("option " + a + " needs a value (or is unknown; see --help)");
    const std::string v = argv[++k];
    if (a == "--pass") continue;  // handled above
    auto imperfect = applyImperfectionOption(a, v, &c, &imperfection);
    if (!imperfect) return R::failure(imperfect.error());
    if (*imperfect) continue;
    auto gnss = applyGnssOption(a, v, &o.gnss);
    if (!gnss) return R::failure(gnss.error());
    if (*gnss) continue;
    if (a == "--bag") {
      o.bag.path = v;
      continue;
    }
    if (a == "--kitti") {
      o.kitti_dir = v;
      continue;
    }
    if (a == "--map-pose-error") {
      auto m = sim::parseMapPoseErrorMode(v);
      if (!m) return R::failure("option --map-pose-error: " + m.error());
      o.map_pose_error.mode = *m;
      continue;
    }
    if (a == "--route") {
      auto nodes = parseRoute(v);
      if (!nodes) return R::failure(nodes.error());
      c.route.nodes = *nodes;
      continue;
    }
    if (a == "--snow-depth") {
      const size_t comma = v.find(',');
      auto lo = parseOptionNumber(a, v.substr(0, comma));
      auto hi = parseOptionNumber(a, comma == std::string::npos ? "" : v.substr(comma + 1));
      if (!lo || !hi)
        return R::failure("option --snow-depth: expected MIN,MAX in metres, got '" + v + "'");
      c.pass.snow_depth_min_m = *lo;
      c.pass.snow_depth_max_m = *hi;
      continue;
    }
    auto it = num.find(a);
    if (it == num.end()) return R::failure("unknown option " + a + " (see --help)");
    auto d = parseOptionNumber(a, v);
    if (!d) return R::failure(d.error());
    const Status s = it->second(*d);
    if (!s) return R::failure(s.error());
  }
  const double period = 1.0 / c.lidar.rotation_rate_hz;
  c.rig = sensors == 4 ? sim::RigConfig::fourRoofCorners(1.1, 0.72, mount_height, tilt, period)
                       : sim::RigConfig::single(mount_height, 0.0);
  if (azimuth_step > 0.0) {
    const double full = 360.0 * sim::Hdl32eModel::kFiringCycleS * c.lidar.rotation_rate_hz;
    c.lidar.firing_decimation = std::max(1, static_cast<int>(std::lround(azimuth_step / full)));
  }
  if (!o.dry_run && o.bag.path.empty() && o.kitti_dir.empty())
    return R::failure("no output: give --bag FILE and/or --kitti DIR (or --dry-run)");
  const Status mpe = o.map_pose_error.validate();
  if (!mpe) return R::failure(mpe.error());
  if (o.map_pose_error.mode != sim::MapPoseErrorMode::kNone && o.kitti_dir.empty() && !o.dry_run)
    return R::failure("option --map-pose-error " +
                      std::string("realistic changes the poses of --kitti DIR: give --kitti"));
  const Status world_check = checkImperfectionOptions(c, imperfection);
  if (!world_check) return R::failure(world_check.error());
  const Status gnss_check = finishGnssOptions(c.ins.seed, &o.gnss);
  if (!gnss_check) return R::failure(gnss_check.error());
  c.emit_revolutions = o.bag.per_sensor_clouds;
  c.emit_merged = !o.bag.path.empty() && o.bag.merged_cloud;
  c.emit_deskewed = !o.kitti_dir.empty();
  const Status valid = c.validate();
  if (!valid) return R::failure(valid.error());
  return o;
}

}  // namespace tools
}  // namespace gmm_localization
