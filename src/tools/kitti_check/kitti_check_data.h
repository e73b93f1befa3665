#pragma once
// Real-data checks on KITTI-style keyframe dumps (../shared/data/real/kitti07_keyframes): the
// keyframes with their SLAM poses, maps built from a subset of them, and the peers' target
// clouds. Poses are those of the sensor (HDL-64E) in the SLAM world frame; the scans are in the
// sensor frame, so "base_link" below is the sensor frame, about 1.73 m above the ground.

#include <string>
#include <vector>

#include <Eigen/Geometry>

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

/// Every keyframe of `dir` with a pose (graph.txt or poses.txt) and a scan file, read as x,y,z
/// float32 (the keyframe dumps have no intensity).
Result<std::vector<Keyframe>> loadKeyframes(const std::string& dir);

/// Map-builder options as build_map's defaults (paper: 20 cm cells, K <= 2), quiet.
MapBuilderOptions defaultMapOptions(const std::string& output_dir);

/// Builds a Gaussian mixture map from the keyframes of `dir` listed in `use` (every keyframe
/// when empty) into options.output_directory (replacing a map there).
Result<MapBuildStats> buildMap(const std::string& dir, const std::vector<int>& use,
                               MapBuilderOptions options);

/// The listed keyframes' points in the world frame, voxel-downsampled to voxel_m (0: all): the
/// target cloud of the point-cloud peers, built from the same scans as the map.
PointList worldCloud(const std::vector<Keyframe>& keyframes, const std::vector<int>& use,
                     double voxel_m);

}  // namespace kitti_check
}  // namespace gmm_localization
