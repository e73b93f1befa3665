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
  /// One intensity per point, as the input gives it (KITTI's fourth float, a PointCloud2's or
  /// a PCD file's `intensity`), or empty when the input has none. The height layer ignores it;
  /// the reflectivity layer (core/map/reflectivity_layer.h) maps it, and needs it.
  std::vector<float> intensity;
  /// Sensor origin in the map frame [m] when known (a scan); a point-cloud map has none, and
  /// then the builder's range filter does not apply to the batch.
  bool has_sensor_origin = false;
  Eigen::Vector3d sensor_origin_m = Eigen::Vector3d::Zero();
  /// Origin of the vehicle frame in the map frame [m] when known (a scan with a pose): the
  /// reference of the reflectivity layer's ground returns. A point's levelled height above the
  /// vehicle frame is points_m.z - vehicle_origin_m.z, its ground range the horizontal distance
  /// to vehicle_origin_m. The vehicle frame is the scans' own frame for KITTI scans and the
  /// poses' frame (e.g. base_link) for a rosbag; a point-cloud map has none.
  bool has_vehicle_origin = false;
  Eigen::Vector3d vehicle_origin_m = Eigen::Vector3d::Zero();

  /// True when every point has an intensity.
  bool hasIntensity() const { return !points_m.empty() && intensity.size() == points_m.size(); }

  void clear() {
    points_m.clear();
    intensity.clear();
    has_sensor_origin = false;
    sensor_origin_m.setZero();
    has_vehicle_origin = false;
    vehicle_origin_m.setZero();
  }
};

/// Fills `batch` with sensor-frame points moved into the map frame by map_T_sensor (computed in
/// double precision) and sets the sensor origin to map_T_sensor's translation. Non-finite points
/// are kept (the builder counts and drops them). The intensities and the vehicle origin are
/// left as they are (the caller's).
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
