#pragma once
// Preparation of a raw LIDAR scan for registration: non-finite points dropped and counted,
// range and height filters, gravity alignment by the prior's roll and pitch, and a voxel
// downsampling that evens out the point density (near returns are far denser than far ones).

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/core/common/types.h"

namespace gmm_localization {

struct ScanFilterOptions {
  double min_range_m = 3.0;    ///< horizontal distance from base_link below which returns are the
                               ///< vehicle itself [m]
  double max_range_m = 80.0;   ///< horizontal distance beyond which returns are dropped [m]
  double min_height_m = -5.0;  ///< height band kept, relative to base_link after levelling [m]
  double max_height_m = 30.0;
  double voxel_m = 0.2;  ///< voxel edge for downsampling [m]; 0 keeps every point
  /// Search points kept after voxelling (0 = all). Ground returns say little about x, y and
  /// heading, so ground keeps its natural share of them capped at ground_share (1: no bias);
  /// the rest are above-ground structure (each class evenly thinned). Ground: within ground_band_m
  /// of the lowest point of its ground_cell_m square in the levelled scan.
  size_t max_points = 4000;
  double ground_share = 0.2;
  double ground_cell_m = 2.0;
  double ground_band_m = 0.25;

  std::string validate() const;
};

struct FilteredScan {
  PointList points;          ///< search points, levelled base frame: base_link rotated by roll and
                             ///< pitch (no yaw) [m]
  PointList voxels;          ///< every voxel centroid (levelled), for the refinement
  size_t ground_voxels = 0;  ///< voxels classified as ground
  size_t input_points = 0;
  size_t dropped_nonfinite = 0;
  size_t dropped_range = 0;
  size_t dropped_height = 0;
};

/// Filters and levels a scan given in base_link [m], with the vehicle's roll and pitch [rad]
/// (from the prior / IMU). Never fails: an all-NaN scan returns an empty point list.
FilteredScan filterScan(const PointList& base_points, double roll_rad, double pitch_rad,
                        const ScanFilterOptions& options);

/// Splits points into ground (within band_m of the lowest point of their cell_m square) and
/// the rest; returns a flag per point.
std::vector<bool> groundMask(const PointList& levelled, double cell_m, double band_m);

/// At most max_points of `points`: ground in its natural proportion but at most ground_share
/// of them (more only when structure runs short), each class evenly thinned in its original
/// order (deterministic).
PointList selectSearchPoints(const PointList& points, const std::vector<bool>& ground,
                             size_t max_points, double ground_share);

/// Centroid of each occupied voxel of edge voxel_m [m], in a deterministic order.
PointList voxelDownsample(const PointList& points, double voxel_m);

/// Motion compensation of one revolution: each point, captured at time_s[i] [s] relative to the
/// scan stamp, is moved into the base_link frame at the stamp, assuming constant body velocity
/// v [m/s] and angular rate w [rad/s] over the revolution (first order in w * t). times may be
/// empty (no-op). Returns false, changing nothing, when the sizes differ.
bool deskew(PointList& points, const std::vector<float>& time_s, const Eigen::Vector3d& v,
            const Eigen::Vector3d& w);

}  // namespace gmm_localization
