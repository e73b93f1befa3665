#pragma once
// build_map's command line: the options of the map builder plus the input to read.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/mapping/kitti_source.h"
#include "gmm_localization/core/mapping/map_builder.h"

namespace gmm_localization {
namespace tools {

enum class InputKind { kNone, kPcd, kKitti, kBag, kSynthetic };

struct BagInputOptions {
  std::string path;
  std::string cloud_topic = "/velodyne_points";
  std::string pose_topic = "/ground_truth/odom";
  std::string pose_tf_parent, pose_tf_child;  ///< --pose-tf PARENT,CHILD: poses from /tf
  bool has_extrinsic = false;
  Eigen::Isometry3d pose_T_cloud = Eigen::Isometry3d::Identity();  ///< --extrinsic
  double max_pose_gap_s = 0.25;  ///< refuse to interpolate across a longer gap
  int every = 1;                 ///< use every N-th scan
  bool deskew = true;            ///< use the per-point times when present
  std::string time_field;        ///< --time-field: the only one looked at (empty: any known)
};

struct SyntheticStreetOptions {
  double length_m = 1000.0;
  uint32_t seed = 1;
  double scan_spacing_m = 1.0;    ///< distance driven between scans
  double azimuth_step_deg = 0.2;  ///< per laser per revolution
};

struct BuildMapConfig {
  MapBuilderOptions builder;
  InputKind input = InputKind::kNone;
  std::vector<std::string> pcd_paths;  ///< --pcd, repeatable: files or directories of *.pcd
  size_t pcd_batch_points = 1000000;
  /// --transform: the PCD files' frame in the world frame, applied before the offset.
  Eigen::Isometry3d pcd_world_T_file = Eigen::Isometry3d::Identity();
  double pcd_max_abs_z_m = 3000.0;  ///< --max-abs-z: PCD points beyond are dropped, counted
  KittiSourceOptions kitti;
  std::string kitti_calib;  ///< KITTI odometry calib.txt (camera poses -> Velodyne, z up)
  BagInputOptions bag;
  SyntheticStreetOptions synthetic;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  ///< subtracted from every input point
  bool quiet = false;
  bool help = false;
};

const char* buildMapHelp();  // build_map_help.cpp

/// The cell sizes a map may have, "[min, max] m": the map format's bounds (map_format.h),
/// which the manifest reader enforces, so that build_map never writes a map the map server
/// cannot open.
std::string resolutionRange();

/// Parses argv; fails with a message naming the option. `help` set: print buildMapHelp().
Result<BuildMapConfig> parseBuildMapArgs(int argc, char** argv);

/// Empty when the map layer's options fit the input, else why (build_map_layer_args.cpp):
/// `reflectivity_only` names an option of the reflectivity layer given (empty: none).
std::string checkLayerArgs(const BuildMapConfig& config, const std::string& reflectivity_only);
/// A MapBuilderOptions::validate() reason with the option that sets the reflectivity layer's
/// field it names in front ("--ground-range: reflectivity.max_range_m=0 must be ..."); other
/// reasons are returned as they are.
std::string withLayerOption(const std::string& error);

/// "a,b,c" -> doubles (exactly `count` of them).
Result<std::vector<double>> parseNumberList(const std::string& option, const std::string& text,
                                            size_t count);
/// "x,y,z,roll,pitch,yaw" [m, deg] or "x,y,z,qx,qy,qz,qw" -> transform.
Result<Eigen::Isometry3d> parseTransform(const std::string& option, const std::string& text);

}  // namespace tools
}  // namespace gmm_localization
