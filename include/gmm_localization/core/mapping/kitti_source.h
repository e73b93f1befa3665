#pragma once
// KITTI-style scan directories as a PointBatchSource for the map builder (ROS-free).
//
// Scans: scan i is `<dir>/NNNNNN.bin` or `<dir>/NNNNNN/points.bin` (keyframe dumps such as
// ../shared/data/real/kitti07_keyframes), NNNNNN = i zero-padded to 6 digits; when `<dir>`
// has a `velodyne/` subdirectory (a KITTI odometry sequence, the simulator's KITTI output) the
// scans are read from there and the poses default to `<dir>/poses.txt`. Each is little-endian
// float32 records, x y z intensity (xyzi, KITTI's format, 16 bytes) or x y z (xyz, 12 bytes), in
// the sensor frame [m]. KittiFields::kAuto: scans under `velodyne/` are KITTI's xyzi,
// `NNNNNN/points.bin` are the keyframe dumps' xyz; elsewhere (readKittiScan) the file size
// decides: divisible by 16 only -> xyzi, by 12 only -> xyz; divisible by both (a multiple of
// 48 bytes) is ambiguous and fails: pass the layout.
//
// Poses: one pose per scan, either
//  - KITTI odometry: 12 numbers per line, the row-major 3x4 [R | t] of scan i on line i
//    (0-based, blank and '#' lines skipped), or
//  - graph lines `id x y z qx qy qz qw` (id: digits, optionally prefixed, e.g. `v3`): the pose
//    of scan `id`, translation [m] and unit quaternion (normalised on reading).
// The map-frame pose of scan i is map_T_world * pose_i * pose_T_sensor. KITTI odometry's
// ground-truth poses are those of camera 0 in a y-down, z-forward world: pass its calibration
// (readKittiCalibTr) as pose_T_sensor = Tr and map_T_world = Tr^-1, so the map frame is the
// first Velodyne frame (z up). The keyframe graphs are Velodyne poses already (identity).

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/mapping/point_batch.h"

namespace gmm_localization {

enum class KittiFields { kAuto, kXyz, kXyzi };

struct KittiSourceOptions {
  std::string scans_directory;
  std::string poses_file;  ///< empty: <scans_directory>/graph.txt, else poses.txt
  KittiFields fields = KittiFields::kAuto;
  std::vector<int> scans;  ///< scan indices to use; empty: every scan with a pose and a file
  Eigen::Isometry3d pose_T_sensor = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d map_T_world = Eigen::Isometry3d::Identity();
};

/// Pose per scan index from either poses format (see above); fails naming the file and line.
Result<std::map<int, Eigen::Isometry3d>> readKittiPoses(const std::string& path);
/// The `Tr:` (velodyne -> camera 0) line of a KITTI odometry calib.txt.
Result<Eigen::Isometry3d> readKittiCalibTr(const std::string& path);
/// One scan's points in the sensor frame. `intensity`, when given, receives one value per point
/// from xyzi records (the fourth float) and is cleared for xyz records.
Result<std::vector<Eigen::Vector3f>> readKittiScan(const std::string& path, KittiFields fields,
                                                   std::vector<float>* intensity = nullptr);
/// Bound on the indices of one index list, its ranges summed (repeats count): 10^7 (40 MB of
/// ints, far beyond any sequence's scans), so a short argument cannot allocate gigabytes.
constexpr size_t kMaxIndexListSize = 10000000;
/// "0,2,4-7" -> {0, 2, 4, 5, 6, 7}; fails on anything else, and on a list of more than
/// kMaxIndexListSize indices (naming the item that exceeds it).
Result<std::vector<int>> parseIndexList(const std::string& text);

/// Batches carry the scan's intensities when its records are xyzi (else none), and the scan's
/// frame (map_T_sensor) as the vehicle frame: the reflectivity layer's ground height is then
/// given in the scans' frame (0 for scans in a base_link on the ground, about -1.73 m for
/// KITTI's Velodyne frame).
class KittiScanSource : public PointBatchSource {
 public:
  /// Reads the poses, resolves every selected scan's file (fails if a selected scan lacks a
  /// pose or a file); scans are read lazily by next().
  static Result<std::unique_ptr<KittiScanSource>> open(const KittiSourceOptions& options);

  Result<bool> next(PointBatch& batch) override;
  size_t sizeHint() const override { return scans_.size(); }
  std::string describe() const override;

  struct Scan {
    int index;
    std::string path;
    Eigen::Isometry3d map_T_sensor;
  };
  const std::vector<Scan>& scans() const { return scans_; }

 private:
  KittiSourceOptions options_;
  std::vector<Scan> scans_;
  size_t next_ = 0;
};

}  // namespace gmm_localization
