#include "bench_data.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/mapping/kitti_source.h"
#include "gmm_localization/core/raster/raster_region.h"

namespace gmm_localization {
namespace bench {

namespace {
std::string scanPath(const std::string& dir, int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "/velodyne/%06d.bin", index);
  return dir + name;
}
}  // namespace

Result<std::vector<BenchScan>> loadScans(const std::string& dir, int count) {
  using R = Result<std::vector<BenchScan>>;
  auto poses = readKittiPoses(dir + "/poses.txt");
  if (!poses.ok()) return R::failure(poses.error());
  std::vector<int> ids;
  for (const auto& kv : poses.value()) ids.push_back(kv.first);
  if (ids.empty()) return R::failure(dir + "/poses.txt holds no pose");
  std::vector<int> chosen;
  if (count <= 0 || count >= static_cast<int>(ids.size())) {
    chosen = ids;
  } else {
    for (int i = 0; i < count; ++i) chosen.push_back(ids[(i * ids.size()) / count]);
  }
  std::vector<BenchScan> out;
  for (int id : chosen) {
    auto pts = readKittiScan(scanPath(dir, id), KittiFields::kXyzi);
    if (!pts.ok()) return R::failure(pts.error());
    BenchScan s;
    s.index = id;
    s.truth = poses.value().at(id);
    s.points = std::move(pts.value());
    out.push_back(std::move(s));
  }
  return out;
}

Result<ChunkMap> rasterizeAround(const MapStore& store, const std::vector<Eigen::Vector3d>& centres,
                                 double radius_m, const RasterOptions& options,
                                 RasterStats& stats) {
  std::vector<PlanCentre> plan;
  for (const Eigen::Vector3d& c : centres) plan.push_back(c.head<2>());
  RegionStats region;
  auto chunks = rasterizeRegion(store, options, plan, radius_m, 1, &region);
  if (!chunks.ok()) return chunks;
  stats.seconds = region.raster_seconds;
  stats.chunks = region.chunks;
  stats.bytes = region.bytes;
  return chunks;
}

Result<PointList> targetCloud(const std::string& mapping_dir, const Eigen::Vector3d& centre,
                              double radius_m, double voxel_m) {
  using R = Result<PointList>;
  static std::map<std::string, std::map<int, Eigen::Isometry3d>> cache;
  auto it = cache.find(mapping_dir);
  if (it == cache.end()) {
    auto poses = readKittiPoses(mapping_dir + "/poses.txt");
    if (!poses.ok()) return R::failure(poses.error());
    it = cache.emplace(mapping_dir, std::move(poses.value())).first;
  }
  // Mapping scans taken within radius/2 of the centre, every 5th (the scans overlap heavily).
  PointList all;
  int used = 0;
  for (const auto& [id, pose] : it->second) {
    if ((pose.translation() - centre).head<2>().norm() > 0.5 * radius_m || id % 5 != 0) continue;
    auto pts = readKittiScan(scanPath(mapping_dir, id), KittiFields::kXyzi);
    if (!pts.ok()) return R::failure(pts.error());
    for (const Eigen::Vector3f& p : pts.value()) {
      const Eigen::Vector3d q = pose * p.cast<double>();
      if ((q - centre).head<2>().norm() <= radius_m) all.push_back(q.cast<float>());
    }
    ++used;
  }
  if (used == 0) return R::failure("no mapping scan near the test scan");
  return voxelDownsample(all, voxel_m);
}

Pose6 offsetPrior(const Eigen::Isometry3d& truth, double r_m, double h_rad, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Pose6 p = fromIsometry(truth);
  const double rho = r_m * std::sqrt(u(rng)), phi = 2.0 * M_PI * u(rng);
  p.x += rho * std::cos(phi);
  p.y += rho * std::sin(phi);
  p.yaw += (2.0 * u(rng) - 1.0) * h_rad;
  return p;
}

double yawOf(const Eigen::Isometry3d& T) { return std::atan2(T.linear()(1, 0), T.linear()(0, 0)); }

double angleDiff(double a, double b) { return std::atan2(std::sin(a - b), std::cos(a - b)); }

double median(std::vector<double> v) { return percentile(std::move(v), 50.0); }

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double r = p / 100.0 * (v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(r));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (r - i) * (v[j] - v[i]);
}

}  // namespace bench
}  // namespace gmm_localization
