#pragma once
// Statistics of one LIDAR revolution used by sim_validate, computed the same way for real and
// simulated scans (sensor frame, ring per point).

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace tools {

struct RevolutionPoint {
  Eigen::Vector3f p;  ///< sensor frame [m]
  int ring;           ///< 0 = lowest beam
  float intensity;
};

/// Range histogram bin edges [m].
inline const std::array<double, 8>& rangeBinEdges() {
  static const std::array<double, 8> kEdges = {0.0, 2.0, 5.0, 10.0, 20.0, 40.0, 70.0, 120.0};
  return kEdges;
}

struct RevolutionStats {
  size_t points = 0;
  size_t slots = 0;              ///< firings x 32 (0 if unknown)
  double ground_share = 0.0;     ///< within 0.15 m of the fitted ground plane
  double sensor_height_m = 0.0;  ///< distance from the sensor to the ground plane
  std::array<double, 8>
      ring_ground_range{};             ///< median ground distance of rings 0..7 [m] (0 = none)
  std::array<double, 7> range_hist{};  ///< share of points per range bin
  double median_range_m = 0.0;
  double median_intensity = 0.0;
  double mean_intensity = 0.0;
};

/// Reads a PCD v0.7 file with binary float x y z intensity (fields in that order).
Result<std::vector<Eigen::Vector4f>> readPcdXyzi(const std::string& path);

/// Ground plane by RANSAC (normal within 25 deg of the sensor's z axis, seeded, deterministic).
RevolutionStats revolutionStats(const std::vector<RevolutionPoint>& points, size_t slots);

}  // namespace tools
}  // namespace gmm_localization
