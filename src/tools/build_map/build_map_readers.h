#pragma once
// PointBatchSource implementations that need PCL or ROS (the KITTI reader is in the core,
// core/kitti_source.h; the synthetic street is in build_map_synthetic.h). Library target
// gmm_map_readers (cmake/tools/map.cmake), for build_map and any other tool or node.

#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/mapping/point_batch.h"

namespace gmm_localization {
namespace tools {

/// A PCD point-cloud map (any point type with x, y, z), in the map frame, fed in batches of
/// `batch_points`. No sensor origin (range filters do not apply). `offset_m` is subtracted
/// from every point. PCL reads the whole file into memory on open().
class PcdSource : public PointBatchSource {
 public:
  static Result<std::unique_ptr<PcdSource>> open(const std::string& path, size_t batch_points,
                                                 const Eigen::Vector3d& offset_m);
  ~PcdSource() override;
  Result<bool> next(PointBatch& batch) override;
  size_t sizeHint() const override;
  std::string describe() const override;
  size_t points() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct RosbagSourceOptions {
  std::string path;
  std::string cloud_topic = "/velodyne_points";
  std::string pose_topic = "/ground_truth/odom";
  /// The cloud frame in the pose's child frame. Unset: looked up in /tf_static (a direct edge
  /// between the two frames), identity when the frame ids are equal or the pose type has no
  /// child frame (PoseStamped), else open() fails naming both frames.
  bool has_extrinsic = false;
  Eigen::Isometry3d pose_T_cloud = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d map_T_world = Eigen::Isometry3d::Identity();  ///< left-multiplies poses
  double max_pose_gap_s = 0.25;
  int every = 1;
  /// Deskew (motion-compensate) scans whose clouds carry a per-point time field: each point is
  /// moved with the pose interpolated at header.stamp + time (time in seconds relative to the
  /// stamp, FLOAT32/FLOAT64, the Velodyne driver's and the simulator's convention; resolved to
  /// 1 ms). Clouds without the field are used as they are.
  bool deskew = true;
  std::string time_field = "time";
};

/// A rosbag with sensor_msgs/PointCloud2 scans and a pose topic (nav_msgs/Odometry,
/// geometry_msgs/PoseStamped or PoseWithCovarianceStamped). Each scan's pose is interpolated
/// at its header stamp (linear in position, slerp in rotation) between the two poses around it.
/// With a per-point time field the scan is deskewed (see RosbagSourceOptions::deskew). The
/// batch's sensor origin is the sensor's position at the stamp (used by the range filter).
/// Scans outside the poses' time span or across a gap longer than max_pose_gap_s, and
/// malformed clouds (no float x/y/z fields, sizes that disagree), are skipped and counted
/// (skipped()), never guessed.
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
