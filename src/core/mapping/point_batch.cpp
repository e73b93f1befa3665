#include "gmm_localization/core/mapping/point_batch.h"

namespace gmm_localization {

void setBatchFromSensorFrame(const std::vector<Eigen::Vector3f>& points_sensor,
                             const Eigen::Isometry3d& map_T_sensor, PointBatch& batch) {
  batch.points_m.resize(points_sensor.size());
  const Eigen::Matrix3d rotation = map_T_sensor.linear();
  const Eigen::Vector3d translation = map_T_sensor.translation();
  for (size_t i = 0; i < points_sensor.size(); ++i) {
    batch.points_m[i] = (rotation * points_sensor[i].cast<double>() + translation).cast<float>();
  }
  batch.has_sensor_origin = true;
  batch.sensor_origin_m = translation;
}

}  // namespace gmm_localization
