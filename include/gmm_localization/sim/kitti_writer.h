#pragma once
// KittiWriter: the direct path into build_map. Writes a KITTI-style directory:
//   velodyne/NNNNNN.bin   float32 x, y, z, intensity per point, base_link frame at the scan stamp
//   poses.txt             per scan, 12 numbers: the 3x4 row-major base_link -> map pose
//   times.txt             per scan, the stamp [s] (trajectory time)
//   labels/NNNNNN.label   (optional) uint8 PointLabel per point, same order as the .bin

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/sim/lidar_simulator.h"

namespace gmm_localization {
namespace sim {

class KittiWriter {
 public:
  /// Creates `dir` (and parents) and its velodyne/ (and labels/) subdirectories.
  static Result<std::unique_ptr<KittiWriter>> open(const std::string& dir, bool write_labels);
  ~KittiWriter();
  Status write(const std::vector<LidarPoint>& points, const Eigen::Isometry3d& base_to_map,
               double stamp);
  Status close();
  size_t scans() const { return count_; }
  /// Writes `poses` to `path` in the poses.txt format (12 numbers per line, row-major 3x4).
  static Status writePoses(const std::string& path, const std::vector<Eigen::Isometry3d>& poses);

 private:
  KittiWriter() = default;
  std::string dir_;
  bool labels_ = false;
  std::FILE* poses_ = nullptr;
  std::FILE* times_ = nullptr;
  size_t count_ = 0;
};

}  // namespace sim
}  // namespace gmm_localization
