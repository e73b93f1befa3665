#pragma once
// Preparation of a raw LIDAR scan for registration: non-finite points dropped and counted,
// range and height filters, gravity alignment by the prior's roll and pitch, and a voxel
// downsampling that evens out the point density (near returns are far denser than far ones).

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace gmm_localization {

using PointList = std::vector<Eigen::Vector3f>;

struct ScanFilterOptions {
  double min_range_m = 3.0;    ///< horizontal distance from base_link below which returns are the
                               ///< vehicle itself [m]
  double max_range_m = 80.0;   ///< horizontal distance beyond which returns are dropped [m]
  double min_height_m = -5.0;  ///< height band kept, relative to base_link after levelling [m]
  double max_height_m = 30.0;
  double voxel_m = 0.2;   ///< voxel edge for downsampling [m]; 0 keeps every point
  size_t max_points = 0;  ///< keep at most this many (evenly spaced after voxelling); 0 = all

  std::string validate() const;
};

struct FilteredScan {
  PointList points;  ///< levelled base frame: base_link rotated by roll and pitch (no yaw) [m]
  size_t input_points = 0;
  size_t dropped_nonfinite = 0;
  size_t dropped_range = 0;
  size_t dropped_height = 0;
};

/// Filters and levels a scan given in base_link [m], with the vehicle's roll and pitch [rad]
/// (from the prior / IMU). Never fails: an all-NaN scan returns an empty point list.
FilteredScan filterScan(const PointList& base_points, double roll_rad, double pitch_rad,
                        const ScanFilterOptions& options);

/// Centroid of each occupied voxel of edge voxel_m [m], in a deterministic order.
PointList voxelDownsample(const PointList& points, double voxel_m);

/// Motion compensation of one revolution: each point, captured at time_s[i] [s] relative to the
/// scan stamp, is moved into the base_link frame at the stamp, assuming constant body velocity
/// v [m/s] and angular rate w [rad/s] over the revolution (first order in w * t). times may be
/// empty (no-op). Returns false, changing nothing, when the sizes differ.
bool deskew(PointList& points, const std::vector<float>& time_s, const Eigen::Vector3d& v,
            const Eigen::Vector3d& w);

}  // namespace gmm_localization
