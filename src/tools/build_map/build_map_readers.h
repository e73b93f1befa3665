#pragma once
// PointBatchSource implementations for PCD maps and rosbags (the KITTI reader is in the core,
// core/mapping/kitti_source.h; the synthetic street is in build_map_synthetic.h). Library target
// gmm_map_readers (cmake/tools/map.cmake), for build_map and any other tool or node.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/mapping/point_batch.h"

namespace gmm_localization {
namespace tools {

struct PcdSourceOptions {
  /// PCD files and directories; a directory stands for every *.pcd file in it (not recursive),
  /// sorted by name (Autoware's tiled maps). Files are read in the order given.
  std::vector<std::string> paths;
  size_t batch_points = 1000000;  ///< points per batch (batches never span two files)
  /// Applied first, in double: the file's frame in the world frame (p_world = world_T_file *
  /// p_file), for maps whose frame is not gravity-aligned (FAST-LIO's first IMU frame).
  Eigen::Isometry3d world_T_file = Eigen::Isometry3d::Identity();
  /// Subtracted next, in double (p_map = p_world - offset_m), before narrowing to float: a UTM
  /// origin keeps map coordinates small. It is the map's georeference (map + offset = world).
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  /// Points with map-frame |z| above this [m] are dropped and counted (junk returns far above
  /// or below the map would otherwise make absurd cells), as are non-finite points.
  double max_abs_z_m = 3000.0;
};

/// A point-cloud map in one or more PCD files (ascii, binary or binary_compressed; x, y, z of
/// any numeric type, read in double: pcd_reader.h), fed in batches without sensor origin
/// (range filters do not apply) nor vehicle origin (no reflectivity layer), with the files'
/// intensities when they have a field for them (PcdHeader::intensity). open() checks every file
/// (header, data size, compressed stream, ascii lines) before the first point is produced, so a bad
/// file fails the build before it starts, with an error naming the file. Files are then read one at
/// a time, in batches (only a binary_compressed file is held whole in memory, decompressed).
/// Dropped points (non-finite, |z| beyond max_abs_z_m) are counted (dropped()); next() fails
/// at the end when no point at all was kept.
class PcdSource : public PointBatchSource {
 public:
  static Result<std::unique_ptr<PcdSource>> open(const PcdSourceOptions& options);
  ~PcdSource() override;
  Result<bool> next(PointBatch& batch) override;
  size_t sizeHint() const override;
  std::string describe() const override;
  size_t points() const;  ///< in the files' headers
  const std::vector<std::string>& files() const;
  /// Points dropped so far, and why (one line), e.g. "3 (2 non-finite, 1 out of range ...)".
  std::string dropped() const;
  uint64_t droppedPoints() const;
  /// Warnings since the last call, one sentence each: oddities of the files (data after the
  /// last point, a VIEWPOINT that is not identity), float32 coordinates too large for
  /// centimetres, and at the end of the input the dropped points and map-frame coordinates
  /// far from the origin (float32 precision).
  std::vector<std::string> takeWarnings();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct RosbagSourceOptions {
  std::string path;
  std::string cloud_topic = "/velodyne_points";
  /// nav_msgs/Odometry, geometry_msgs/PoseStamped or PoseWithCovarianceStamped (ignored when
  /// pose_tf_child is set).
  std::string pose_topic = "/ground_truth/odom";
  /// Set: the poses are those of pose_tf_child in pose_tf_parent from the bag's /tf (composed
  /// through the TF tree with /tf_static, e.g. map -> odom -> base_link), looked up at every
  /// stamp of a /tf transform on that chain.
  std::string pose_tf_parent;
  std::string pose_tf_child;
  /// The cloud frame in the pose's child frame. Unset: composed from /tf_static (any chain of
  /// static transforms between the two frames, in either direction), identity when the frame
  /// ids are equal or the pose type has no child frame (PoseStamped), else next() fails naming
  /// both frames.
  bool has_extrinsic = false;
  Eigen::Isometry3d pose_T_cloud = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d map_T_world = Eigen::Isometry3d::Identity();  ///< left-multiplies poses
  double max_pose_gap_s = 0.25;
  int every = 1;
  /// Deskew (motion-compensate) scans whose clouds carry per-point times: each point is moved
  /// with the pose interpolated at header.stamp + its time (resolved to 1 ms). The clouds are
  /// read by the matcher's reader (ros/cloud_conversion.h), so every time field it knows
  /// works: velodyne `time`, Ouster `t`, Hesai, RoboSense and Livox `timestamp`, relative or
  /// absolute. Clouds without times, or with times that make no sense, are used as they are
  /// (counted in skipped()).
  bool deskew = true;
  /// The only time field looked at; empty: the reader's (time, t, timestamp).
  std::string time_field;
};

/// A rosbag with sensor_msgs/PointCloud2 scans and their poses: a pose topic (nav_msgs/Odometry,
/// geometry_msgs/PoseStamped or PoseWithCovarianceStamped) or /tf. Each scan's pose is
/// interpolated at its header stamp (linear in position, slerp in rotation) between the two
/// poses around it. With per-point times the scan is deskewed (see RosbagSourceOptions::deskew).
/// The batch's sensor origin is the sensor's position at the stamp (used by the range filter),
/// its vehicle origin the pose's position at the stamp (the poses' frame is the vehicle frame of
/// the reflectivity layer), and its intensities the clouds' float `intensity` field when they
/// have one.
/// Scans outside the poses' time span or across a gap longer than max_pose_gap_s, and
/// malformed clouds (the reader's reasons: no float x/y/z fields, sizes that disagree), are
/// skipped and counted (skipped()), never guessed.
class RosbagSource : public PointBatchSource {
 public:
  static Result<std::unique_ptr<RosbagSource>> open(const RosbagSourceOptions& options);
  ~RosbagSource() override;
  Result<bool> next(PointBatch& batch) override;
  size_t sizeHint() const override;
  std::string describe() const override;
  /// Scans skipped so far, and why (one line).
  std::string skipped() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tools
}  // namespace gmm_localization
