#pragma once
// Real-data checks on KITTI-style data (keyframe dumps such as ../shared/data/real/
// kitti07_keyframes, or a KITTI odometry sequence's velodyne/ scans): the keyframes with their
// poses, maps built from a subset of them, and the peers' target clouds. Poses are those of the
// sensor (HDL-64E) in the SLAM world frame (or, with a KITTI calibration, in the first Velodyne
// frame); the scans are in the sensor frame, so "base_link" below is the sensor frame, about
// 1.73 m above the ground.

#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "bench/bench_data.h"
#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/mapping/map_builder.h"
#include "gmm_localization/core/matching/scan_filter.h"

namespace gmm_localization {
namespace kitti_check {

struct Keyframe {
  int index = 0;
  std::string path;                                         ///< points file
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();  ///< sensor in world (SLAM)
  PointList points;                                         ///< sensor frame [m]
};

using bench::KittiInput;
using bench::KittiScans;

struct KeyframeSet {
  std::vector<Keyframe> keyframes;
  KittiScans data;  ///< how they were read: layout (and why), poses without a scan file
};

/// Every keyframe of the data set with a pose and a scan file (bench::openKittiInput: records
/// x,y,z,intensity under velodyne/ as KITTI, x,y,z for NNNNNN/points.bin as the keyframe dumps,
/// else by file size or as forced by input.fields; a size that is not a multiple of the record
/// size fails naming the file).
Result<KeyframeSet> loadKeyframes(const KittiInput& input);

/// One line for the report: the layout (and why) and the poses skipped for want of a scan.
std::string describeData(const KittiScans& data);
/// The same on `out` (stderr), a guessed layout as a warning.
void noteData(const KittiScans& data, std::FILE* out);

/// Map-builder options as build_map's defaults (paper: 20 cm cells, K <= 2), quiet.
MapBuilderOptions defaultMapOptions(const std::string& output_dir);

/// Builds a Gaussian mixture map from the keyframes of `data` listed in `use` (every keyframe
/// when empty), read as loadKeyframes read them, into options.output_directory (replacing a
/// map there).
Result<MapBuildStats> buildMap(const KittiScans& data, const std::vector<int>& use,
                               MapBuilderOptions options);

/// The listed keyframes' points in the world frame, voxel-downsampled to voxel_m (0: all): the
/// target cloud of the point-cloud peers, built from the same scans as the map.
PointList worldCloud(const std::vector<Keyframe>& keyframes, const std::vector<int>& use,
                     double voxel_m);

}  // namespace kitti_check
}  // namespace gmm_localization
