#include "kitti_check/kitti_check_data.h"

#include <algorithm>

#include "gmm_localization/core/mapping/kitti_source.h"

namespace gmm_localization {
namespace kitti_check {

namespace {
bool selected(const std::vector<int>& use, int index) {
  return use.empty() || std::find(use.begin(), use.end(), index) != use.end();
}
}  // namespace

Result<std::vector<Keyframe>> loadKeyframes(const std::string& dir) {
  using R = Result<std::vector<Keyframe>>;
  KittiSourceOptions o;
  o.scans_directory = dir;
  o.fields = KittiFields::kXyz;
  auto source = KittiScanSource::open(o);
  if (!source.ok()) return R::failure(source.error());
  std::vector<Keyframe> out;
  for (const KittiScanSource::Scan& s : source.value()->scans()) {
    auto pts = readKittiScan(s.path, KittiFields::kXyz);
    if (!pts.ok()) return R::failure(pts.error());
    Keyframe k;
    k.index = s.index;
    k.path = s.path;
    k.truth = s.map_T_sensor;
    k.points = std::move(pts.value());
    out.push_back(std::move(k));
  }
  if (out.empty()) return R::failure(dir + ": no keyframe with a pose and a scan");
  return out;
}

MapBuilderOptions defaultMapOptions(const std::string& output_dir) {
  MapBuilderOptions o;
  o.output_directory = output_dir;
  o.overwrite = true;
  o.threads = 1;
  o.spill_buffer_bytes = size_t{16} << 20;
  return o;
}

Result<MapBuildStats> buildMap(const std::string& dir, const std::vector<int>& use,
                               MapBuilderOptions options) {
  using R = Result<MapBuildStats>;
  KittiSourceOptions k;
  k.scans_directory = dir;
  k.fields = KittiFields::kXyz;
  k.scans = use;
  auto source = KittiScanSource::open(k);
  if (!source.ok()) return R::failure(source.error());
  options.provenance = "kitti_check from " + source.value()->describe();
  auto builder = MapBuilder::create(options);
  if (!builder.ok()) return R::failure(builder.error());
  const Status added = addAllBatches(*source.value(), *builder.value());
  if (!added.ok()) return R::failure(added.error());
  return builder.value()->finish();
}

PointList worldCloud(const std::vector<Keyframe>& keyframes, const std::vector<int>& use,
                     double voxel_m) {
  PointList all;
  for (const Keyframe& k : keyframes) {
    if (!selected(use, k.index)) continue;
    for (const Eigen::Vector3f& p : k.points) {
      if (p.allFinite()) all.push_back((k.truth * p.cast<double>()).cast<float>());
    }
  }
  return voxel_m > 0.0 ? voxelDownsample(all, voxel_m) : all;
}

}  // namespace kitti_check
}  // namespace gmm_localization
