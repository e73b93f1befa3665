#include "bench_data.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/mapping/kitti_source.h"
#include "gmm_localization/core/raster/rasterizer.h"

namespace gmm_localization {
namespace bench {

namespace {
double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

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
  const MapGeometry& g = store.geometry();
  ChunkMap chunks(g, options);
  std::set<ChunkId> wanted;
  const double chunk_m = g.resolution_m * options.chunkCells();
  for (const Eigen::Vector3d& c : centres) {
    const CellIndex lo = g.cellAt(c.x() - radius_m, c.y() - radius_m);
    const CellIndex hi = g.cellAt(c.x() + radius_m, c.y() + radius_m);
    for (int64_t cy = lo.y >> options.chunk_shift; cy <= (hi.y >> options.chunk_shift); ++cy) {
      for (int64_t cx = lo.x >> options.chunk_shift; cx <= (hi.x >> options.chunk_shift); ++cx) {
        const Eigen::Vector2d centre =
            g.cellCenter({cx << options.chunk_shift, cy << options.chunk_shift}) +
            Eigen::Vector2d::Constant(0.5 * chunk_m);
        if ((centre - c.head<2>()).norm() <= radius_m + chunk_m) {
          wanted.insert({static_cast<int32_t>(cx), static_cast<int32_t>(cy)});
        }
      }
    }
  }
  // Tiles covering the wanted chunks and their +x/+y reach.
  GmmMap map(g);
  std::set<TileId> tiles;
  const int reach = (1 << options.num_layers);
  for (const ChunkId& id : wanted) {
    const CellIndex o{static_cast<int64_t>(id.x) << options.chunk_shift,
                      static_cast<int64_t>(id.y) << options.chunk_shift};
    const TileId t0 = g.tileOf(o);
    const TileId t1 =
        g.tileOf({o.x + options.chunkCells() + reach, o.y + options.chunkCells() + reach});
    for (int32_t ty = t0.y; ty <= t1.y; ++ty) {
      for (int32_t tx = t0.x; tx <= t1.x; ++tx) tiles.insert({tx, ty});
    }
  }
  for (const TileId& t : tiles) {
    if (!store.hasTile(t)) continue;
    auto tile = store.loadTile(t);
    if (!tile.ok()) return Result<ChunkMap>::failure(tile.error());
    map.insert(tile.value());
  }
  const double t0 = now();
  for (const ChunkId& id : wanted) {
    auto chunk = rasterizeChunk(map, id, options);
    if (!chunk.ok()) return Result<ChunkMap>::failure(chunk.error());
    chunks.insert(chunk.value());
  }
  stats.seconds = now() - t0;
  stats.chunks = wanted.size();
  stats.bytes = chunks.bytes();
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
