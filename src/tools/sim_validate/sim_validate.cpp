// sim_validate: compares simulated single HDL-32E revolutions with real ones (PCD files) and
// prints a markdown table: points per revolution, share of ground points, ground distance and
// spacing of the lowest rings, range histogram, intensities.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "common/cli_args.h"
#include "gmm_localization/sim/hdl32e.h"
#include "gmm_localization/sim/lidar_simulator.h"
#include "gmm_localization/sim/route.h"
#include "gmm_localization/sim/town.h"
#include "gmm_localization/sim/trajectory.h"
#include "gmm_localization/sim/world.h"
#include "sim_validate/sim_validate_stats.h"

using namespace gmm_localization;
using tools::RevolutionStats;

namespace {

const char* kHelp = R"(sim_validate: compare simulated HDL-32E revolutions with real ones.

Usage: sim_validate [--real DIR] [--revolutions N] [--town-seed N] [--town-size M]
                    [--pass mapping|downtown|snowy] [--mount-height M] [--threads N]
  --real DIR         folder of real revolutions: PCD v0.7 binary, fields x y z intensity,
                     32 points per firing in laser order with zeros for missing returns
                     (default ../shared/data/real/hdl32e_pair)
  --revolutions N    simulated revolutions spread along the route (20)
  --mount-height M   simulated sensor height; default: the real scans' fitted ground distance
Prints a markdown table to stdout.
)";

RevolutionStats average(const std::vector<RevolutionStats>& v) {
  RevolutionStats a;
  if (v.empty()) return a;
  const double n = static_cast<double>(v.size());
  for (const RevolutionStats& s : v) {
    a.points += s.points;
    a.slots += s.slots;
    a.ground_share += s.ground_share / n;
    a.sensor_height_m += s.sensor_height_m / n;
    a.median_range_m += s.median_range_m / n;
    a.median_intensity += s.median_intensity / n;
    a.mean_intensity += s.mean_intensity / n;
    for (size_t k = 0; k < a.range_hist.size(); ++k) a.range_hist[k] += s.range_hist[k] / n;
  }
  a.points /= v.size();
  a.slots /= v.size();
  for (int r = 0; r < 8; ++r) {  // median over revolutions that saw the ring on the ground
    std::vector<double> xs;
    for (const RevolutionStats& s : v)
      if (s.ring_ground_range[r] > 0.0) xs.push_back(s.ring_ground_range[r]);
    std::sort(xs.begin(), xs.end());
    a.ring_ground_range[r] = xs.empty() ? 0.0 : xs[xs.size() / 2];
  }
  return a;
}

std::string rings(const RevolutionStats& s, bool spacing) {
  std::string out;
  char buf[32];
  for (int r = 0; r < (spacing ? 7 : 8); ++r) {
    double v = s.ring_ground_range[r];
    if (spacing)
      v = (s.ring_ground_range[r] > 0 && s.ring_ground_range[r + 1] > 0)
              ? s.ring_ground_range[r + 1] - s.ring_ground_range[r]
              : 0.0;
    std::snprintf(buf, sizeof(buf), "%s%.2f", r ? ", " : "", v);
    out += v > 0.0 ? buf : (r ? ", -" : "-");
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string real_dir = "../shared/data/real/hdl32e_pair";
  int revolutions = 20, threads = 2;
  double mount_height = 0.0;
  sim::TownConfig town_cfg;
  town_cfg.size_x_m = town_cfg.size_y_m = 1000.0;
  sim::PassType pass = sim::PassType::kDowntown;
  gmm_localization::tools::NormalizedArgs args(argc, argv);
  argc = args.argc();
  argv = args.argv();
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--help" || a == "-h") {
      std::fputs(kHelp, stdout);
      return 0;
    }
    if (k + 1 >= argc) {
      std::fprintf(stderr, "sim_validate: %s needs a value (or is unknown; see --help)\n",
                   a.c_str());
      return gmm_localization::tools::kExitUsage;
    }
    const std::string v = argv[++k];
    if (a == "--real")
      real_dir = v;
    else if (a == "--revolutions")
      revolutions = std::max(1, std::atoi(v.c_str()));
    else if (a == "--town-seed")
      town_cfg.seed = std::strtoull(v.c_str(), nullptr, 10);
    else if (a == "--town-size")
      town_cfg.size_x_m = town_cfg.size_y_m = std::atof(v.c_str());
    else if (a == "--mount-height")
      mount_height = std::atof(v.c_str());
    else if (a == "--threads")
      threads = std::max(1, std::atoi(v.c_str()));
    else if (a == "--pass") {
      auto t = sim::parsePassType(v);
      if (!t) {
        std::fprintf(stderr, "sim_validate: %s\n", t.error().c_str());
        return gmm_localization::tools::kExitUsage;
      }
      pass = *t;
    } else {
      std::fprintf(stderr, "sim_validate: unknown option %s\n%s", a.c_str(), kHelp);
      return gmm_localization::tools::kExitUsage;
    }
  }

  // Real revolutions: laser id = index mod 32 (the files keep empty returns as zeros).
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(real_dir, ec))
    if (e.path().extension() == ".pcd") files.push_back(e.path().string());
  if (ec || files.empty()) {
    std::fprintf(stderr, "sim_validate: no .pcd files in %s\n", real_dir.c_str());
    return 1;
  }
  std::sort(files.begin(), files.end());
  std::vector<RevolutionStats> real;
  for (const std::string& f : files) {
    auto pts = tools::readPcdXyzi(f);
    if (!pts) {
      std::fprintf(stderr, "sim_validate: %s\n", pts.error().c_str());
      return 1;
    }
    std::vector<tools::RevolutionPoint> rp;
    for (size_t i = 0; i < pts->size(); ++i) {
      const Eigen::Vector4f& q = (*pts)[i];
      if (q.head<3>().norm() < 0.01f || !q.allFinite()) continue;
      rp.push_back({q.head<3>(), sim::Hdl32eModel::ringOfLaser(static_cast<int>(i % 32)), q.w()});
    }
    real.push_back(tools::revolutionStats(rp, pts->size()));
  }
  const RevolutionStats r = average(real);
  if (mount_height <= 0.0) mount_height = std::clamp(r.sensor_height_m, 1.0, 3.0);

  // Simulated revolutions of one roof-centre HDL-32E spread along the route.
  auto town = sim::Town::generate(town_cfg);
  if (!town) {
    std::fprintf(stderr, "sim_validate: %s\n", town.error().c_str());
    return 1;
  }
  sim::RouteConfig route_cfg;
  route_cfg.length_m = 2000.0;
  auto route = sim::Route::plan(*town, route_cfg);
  if (!route) {
    std::fprintf(stderr, "sim_validate: %s\n", route.error().c_str());
    return 1;
  }
  auto traj = sim::Trajectory::create(*town, *route, sim::KinematicsConfig());
  if (!traj) {
    std::fprintf(stderr, "sim_validate: %s\n", traj.error().c_str());
    return 1;
  }
  auto world = sim::World::create(*town, sim::PassConfig::defaults(pass), threads);
  if (!world) {
    std::fprintf(stderr, "sim_validate: %s\n", world.error().c_str());
    return 1;
  }
  sim::RigConfig rig = sim::RigConfig::single(mount_height, 0.0);
  rig.ego_boxes.clear();  // a mast-mounted sensor that sees the ground all round, like the real one
  sim::LidarSimulator lidar(*world, *traj, rig, sim::Hdl32eConfig(), 99, threads);
  std::vector<RevolutionStats> simulated;
  const int64_t last =
      static_cast<int64_t>(traj->duration() / lidar.model().revolutionPeriod()) - 2;
  for (int k = 0; k < revolutions; ++k) {
    const int64_t index = 50 + (last - 50) * k / std::max(1, revolutions);
    const sim::SensorRevolution rev = lidar.simulate(0, index);
    std::vector<tools::RevolutionPoint> rp;
    rp.reserve(rev.points.size());
    for (const sim::LidarPoint& p : rev.points)
      rp.push_back({Eigen::Vector3f(p.x, p.y, p.z), p.ring, p.intensity});
    simulated.push_back(tools::revolutionStats(rp, rev.rays));
  }
  const RevolutionStats s = average(simulated);

  std::printf(
      "| HDL-32E revolution | real (%zu scans, %s) | simulated (%d revolutions, %s pass) |\n",
      real.size(), std::filesystem::path(real_dir).filename().c_str(), revolutions,
      sim::passTypeName(pass));
  std::printf("|---|---|---|\n");
  std::printf("| firing slots (firings x 32) | %zu | %zu |\n", r.slots, s.slots);
  std::printf("| points per revolution | %zu | %zu |\n", r.points, s.points);
  std::printf("| returns / slots | %.1f%% | %.1f%% |\n",
              100.0 * r.points / std::max<size_t>(1, r.slots),
              100.0 * s.points / std::max<size_t>(1, s.slots));
  std::printf("| sensor height over fitted ground [m] | %.2f | %.2f |\n", r.sensor_height_m,
              s.sensor_height_m);
  std::printf("| ground points (within 0.15 m of plane) | %.1f%% | %.1f%% |\n",
              100.0 * r.ground_share, 100.0 * s.ground_share);
  std::printf("| ground distance of rings 0-7 [m] | %s | %s |\n", rings(r, false).c_str(),
              rings(s, false).c_str());
  std::printf("| ring spacing on the ground, rings 0-7 [m] | %s | %s |\n", rings(r, true).c_str(),
              rings(s, true).c_str());
  std::printf("| median range [m] | %.1f | %.1f |\n", r.median_range_m, s.median_range_m);
  const auto& e = tools::rangeBinEdges();
  for (size_t b = 0; b + 1 < e.size(); ++b)
    std::printf("| range %g-%g m | %.1f%% | %.1f%% |\n", e[b], e[b + 1], 100.0 * r.range_hist[b],
                100.0 * s.range_hist[b]);
  std::printf("| intensity median / mean | %.0f / %.1f | %.0f / %.1f |\n", r.median_intensity,
              r.mean_intensity, s.median_intensity, s.mean_intensity);
  return 0;
}
