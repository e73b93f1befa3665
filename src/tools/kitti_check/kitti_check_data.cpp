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

Result<KeyframeSet> loadKeyframes(const KittiInput& input) {
  using R = Result<KeyframeSet>;
  auto data = bench::openKittiInput(input);
  if (!data.ok()) return R::failure(data.error());
  KeyframeSet out;
  out.data = std::move(data.value());
  for (const KittiScanSource::Scan& s : out.data.scans) {
    auto pts = readKittiScan(s.path, out.data.source.fields);
    if (!pts.ok()) return R::failure(pts.error());
    Keyframe k;
    k.index = s.index;
    k.path = s.path;
    k.truth = s.map_T_sensor;
    k.points = std::move(pts.value());
    out.keyframes.push_back(std::move(k));
  }
  if (out.keyframes.empty()) return R::failure(input.dir + ": no keyframe with a pose and a scan");
  return out;
}

std::string describeData(const KittiScans& d) {
  std::string line = d.layout;
  if (!d.missing.empty()) {
    line +=
        "; " + std::to_string(d.missing.size()) + " of " + std::to_string(d.poses) +
        " poses have no scan file and are skipped (first: " + std::to_string(d.missing.front()) +
        ")";
  }
  return line;
}

void noteData(const KittiScans& d, std::FILE* out) {
  std::fprintf(out, "%s%s\n", d.ambiguous ? "warning: " : "", describeData(d).c_str());
}

MapBuilderOptions defaultMapOptions(const std::string& output_dir) {
  MapBuilderOptions o;
  o.output_directory = output_dir;
  o.overwrite = true;
  o.threads = 1;
  o.spill_buffer_bytes = size_t{16} << 20;
  return o;
}

Result<MapBuildStats> buildMap(const KittiScans& data, const std::vector<int>& use,
                               MapBuilderOptions options) {
  using R = Result<MapBuildStats>;
  KittiSourceOptions k = data.source;  // the layout, poses and calibration resolved
  if (!use.empty()) k.scans = use;
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
