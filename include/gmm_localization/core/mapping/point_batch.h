#pragma once
// The unit of input to the map builder: a batch of points in the map frame, usually one LIDAR
// scan, with the sensor's origin so range filters can apply. Every input (PCD map, KITTI scans,
// rosbag, simulator) is turned into a stream of batches; MapBuilder::addBatch consumes them one
// at a time, so no reader ever needs the whole cloud in memory.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {

struct PointBatch {
  /// Points in the map frame [m]. Keep coordinates local (|x|, |y| below ~100 km) so float
  /// keeps millimetres: subtract a georeference offset before filling the batch.
  std::vector<Eigen::Vector3f> points_m;
  /// Sensor origin in the map frame [m] when known (a scan); a point-cloud map has none, and
  /// then the builder's range filter does not apply to the batch.
  bool has_sensor_origin = false;
  Eigen::Vector3d sensor_origin_m = Eigen::Vector3d::Zero();

  void clear() {
    points_m.clear();
    has_sensor_origin = false;
    sensor_origin_m.setZero();
  }
};

/// Fills `batch` with sensor-frame points moved into the map frame by map_T_sensor (computed in
/// double precision) and sets the sensor origin to map_T_sensor's translation. Non-finite points
/// are kept (the builder counts and drops them).
void setBatchFromSensorFrame(const std::vector<Eigen::Vector3f>& points_sensor,
                             const Eigen::Isometry3d& map_T_sensor, PointBatch& batch);

/// A pull-style stream of batches (a file reader, a simulator pass).
class PointBatchSource {
 public:
  virtual ~PointBatchSource() = default;
  /// Replaces `batch` with the next batch: true when one was produced, false at the end of the
  /// input, a failure (with a reason naming the input) when the input is broken.
  virtual Result<bool> next(PointBatch& batch) = 0;
  /// Number of batches when known in advance (for progress and ETA), else 0.
  virtual size_t sizeHint() const { return 0; }
  /// One line naming the input, for logs and the map's provenance.
  virtual std::string describe() const = 0;
};

}  // namespace gmm_localization
