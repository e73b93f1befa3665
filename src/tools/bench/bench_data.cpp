#include "bench_data.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/raster/raster_region.h"

namespace gmm_localization {
namespace bench {

namespace {

bool isDirectory(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

bool isFile(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

size_t recordBytes(KittiFields f) { return f == KittiFields::kXyzi ? 16 : 12; }

std::string layoutText(KittiFields f) {
  return f == KittiFields::kXyzi ? "x,y,z,intensity (4 float32, 16 bytes per point)"
                                 : "x,y,z (3 float32, 12 bytes per point)";
}

/// The record layout of `scans` (kAuto resolved) and why; fails on files that fit neither.
Result<KittiFields> chooseLayout(const KittiInput& in,
                                 const std::vector<KittiScanSource::Scan>& scans,
                                 const std::vector<uint64_t>& sizes, std::string& why,
                                 bool& ambiguous) {
  using R = Result<KittiFields>;
  ambiguous = false;
  if (in.fields != KittiFields::kAuto) {
    why = "as given (--point-format " + std::string(pointFormatName(in.fields)) + ")";
    return in.fields;
  }
  if (isDirectory(in.dir + "/velodyne")) {
    why = "the scans are under velodyne/ (KITTI's layout)";
    return KittiFields::kXyzi;
  }
  const bool all_keyframes = std::all_of(scans.begin(), scans.end(), [](const auto& s) {
    return std::filesystem::path(s.path).filename() == "points.bin";
  });
  if (all_keyframes) {
    why = "the scans are NNNNNN/points.bin (the keyframe dumps' layout)";
    return KittiFields::kXyz;
  }
  const KittiScanSource::Scan *only12 = nullptr, *only16 = nullptr;
  for (size_t i = 0; i < scans.size(); ++i) {
    const bool by12 = sizes[i] % 12 == 0, by16 = sizes[i] % 16 == 0;
    if (!by12 && !by16) {
      return R::failure("scan file '" + scans[i].path + "': " + std::to_string(sizes[i]) +
                        " bytes is a multiple of neither 12 (x,y,z) nor 16 (x,y,z,intensity) "
                        "bytes: truncated, or not float32 points");
    }
    if (by12 && !by16 && only12 == nullptr) only12 = &scans[i];
    if (by16 && !by12 && only16 == nullptr) only16 = &scans[i];
  }
  if (only12 != nullptr && only16 != nullptr) {
    return R::failure("scan files '" + only12->path + "' (x,y,z by its size) and '" + only16->path +
                      "' (x,y,z,intensity by its size) differ in layout: pass --point-format");
  }
  if (only12 != nullptr) {
    why = "the file sizes are multiples of 12 bytes, not all of 16";
    return KittiFields::kXyz;
  }
  if (only16 != nullptr) {
    why = "the file sizes are multiples of 16 bytes, not all of 12";
    return KittiFields::kXyzi;
  }
  ambiguous = true;
  why =
      "every file size is a multiple of 48 bytes, which fits both layouts: chose KITTI's; "
      "pass --point-format xyz if the files hold x,y,z";
  return KittiFields::kXyzi;
}

}  // namespace

Result<KittiFields> parsePointFormat(const std::string& text) {
  if (text == "auto") return KittiFields::kAuto;
  if (text == "xyz") return KittiFields::kXyz;
  if (text == "xyzi") return KittiFields::kXyzi;
  return Result<KittiFields>::failure("point format '" + text + "': expected auto, xyz or xyzi");
}

const char* pointFormatName(KittiFields fields) {
  switch (fields) {
    case KittiFields::kXyz:
      return "xyz";
    case KittiFields::kXyzi:
      return "xyzi";
    case KittiFields::kAuto:
      break;
  }
  return "auto";
}

Result<KittiScans> openKittiInput(const KittiInput& in) {
  using R = Result<KittiScans>;
  KittiScans out;
  KittiSourceOptions& k = out.source;
  k.scans_directory = in.dir;
  k.poses_file = in.poses_file;
  if (k.poses_file.empty()) {  // the source's default, resolved here to count the poses
    k.poses_file = in.dir + "/graph.txt";
    if (!isFile(k.poses_file)) k.poses_file = in.dir + "/poses.txt";
  }
  if (!in.calib_file.empty()) {  // as build_map --kitti-calib
    auto tr = readKittiCalibTr(in.calib_file);
    if (!tr.ok()) return R::failure(tr.error());
    k.pose_T_sensor = tr.value();
    k.map_T_world = tr->inverse();
  }
  auto poses = readKittiPoses(k.poses_file);
  if (!poses.ok()) return R::failure(poses.error());
  out.poses = poses->size();
  // Every scan with a pose and a file (the source skips poses without one).
  auto source = KittiScanSource::open(k);
  if (!source.ok()) return R::failure(source.error());
  out.scans = source.value()->scans();
  size_t next = 0;
  for (const auto& entry : poses.value()) {
    if (next < out.scans.size() && out.scans[next].index == entry.first) {
      ++next;
    } else {
      out.missing.push_back(entry.first);
    }
  }
  std::vector<uint64_t> sizes;
  for (const KittiScanSource::Scan& s : out.scans) {
    std::error_code ec;
    const uint64_t n = std::filesystem::file_size(s.path, ec);
    if (ec) return R::failure("scan file '" + s.path + "': " + ec.message());
    sizes.push_back(n);
  }
  std::string why;
  auto fields = chooseLayout(in, out.scans, sizes, why, out.ambiguous);
  if (!fields.ok()) return R::failure(fields.error());
  k.fields = fields.value();
  out.layout = "points read as " + layoutText(k.fields) + ": " + why;
  for (size_t i = 0; i < out.scans.size(); ++i) {
    if (sizes[i] % recordBytes(k.fields) != 0) {
      return R::failure("scan file '" + out.scans[i].path + "': " + std::to_string(sizes[i]) +
                        " bytes is not a multiple of " + std::to_string(recordBytes(k.fields)) +
                        " (" + out.layout +
                        "); truncated, or another layout: --point-format xyz|xyzi");
    }
  }
  for (const KittiScanSource::Scan& s : out.scans) k.scans.push_back(s.index);
  return out;
}

Result<std::vector<BenchScan>> loadScans(const KittiInput& input, int count, KittiScans* data) {
  using R = Result<std::vector<BenchScan>>;
  auto opened = openKittiInput(input);
  if (!opened.ok()) return R::failure(opened.error());
  const std::vector<KittiScanSource::Scan>& all = opened->scans;
  std::vector<size_t> chosen;
  if (count <= 0 || count >= static_cast<int>(all.size())) {
    for (size_t i = 0; i < all.size(); ++i) chosen.push_back(i);
  } else {
    for (int i = 0; i < count; ++i) chosen.push_back((i * all.size()) / count);
  }
  std::vector<BenchScan> out;
  for (size_t i : chosen) {
    BenchScan s;
    const bool xyzi = opened->source.fields == KittiFields::kXyzi;
    auto pts = readKittiScan(all[i].path, opened->source.fields, xyzi ? &s.intensity : nullptr);
    if (!pts.ok()) return R::failure(pts.error());
    s.index = all[i].index;
    s.truth = all[i].map_T_sensor;
    s.points = std::move(pts.value());
    out.push_back(std::move(s));
  }
  if (data != nullptr) *data = std::move(opened.value());
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

std::string describe(const PeerTargetOptions& o) {
  char buf[256];
  std::string which =
      o.stride > 1 ? "whose index is a multiple of " + std::to_string(o.stride) : "(all)";
  if (o.exclude == 0) which += ", except the test scan itself";
  if (o.exclude > 0) {
    which += ", except those within " + std::to_string(o.exclude) + " of the test scan's index";
  }
  std::snprintf(buf, sizeof buf,
                "mapping scans within %.0f m %s, their points within %.0f m, %.2f m voxels",
                0.5 * o.radius_m, which.c_str(), o.radius_m, o.voxel_m);
  return buf;
}

Result<PointList> targetCloud(const KittiScans& mapping, const Eigen::Vector3d& centre,
                              int test_index, const PeerTargetOptions& o) {
  using R = Result<PointList>;
  PointList all;
  int used = 0;
  for (const KittiScanSource::Scan& s : mapping.scans) {
    const Eigen::Isometry3d& pose = s.map_T_sensor;
    if ((pose.translation() - centre).head<2>().norm() > 0.5 * o.radius_m) continue;
    if (o.stride > 1 && s.index % o.stride != 0) continue;
    if (o.exclude >= 0 && std::abs(s.index - test_index) <= o.exclude) continue;
    auto pts = readKittiScan(s.path, mapping.source.fields);
    if (!pts.ok()) return R::failure(pts.error());
    for (const Eigen::Vector3f& p : pts.value()) {
      const Eigen::Vector3d q = pose * p.cast<double>();
      if ((q - centre).head<2>().norm() <= o.radius_m) all.push_back(q.cast<float>());
    }
    ++used;
  }
  if (used == 0) {
    return R::failure("no mapping scan selected near test scan " + std::to_string(test_index) +
                      " (" + describe(o) + ")");
  }
  return voxelDownsample(all, o.voxel_m);
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
