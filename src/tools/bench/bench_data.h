#pragma once
// Data for the registration benchmark: test scans with ground truth from a KITTI-style
// directory (the simulator's localization pass), the rasterized map around them, and target
// point clouds for the point-cloud peers (NDT, GICP) from the mapping pass.

#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {
namespace bench {

struct BenchScan {
  int index = 0;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();  ///< base_link in map
  PointList points;                                         ///< base_link [m]
};

/// `count` scans evenly spread over the directory's scans (all when count <= 0).
Result<std::vector<BenchScan>> loadScans(const std::string& kitti_dir, int count);

struct RasterStats {
  size_t chunks = 0;
  double seconds = 0.0;  ///< total rasterization time (tiles loaded beforehand)
  size_t bytes = 0;
};

/// rasterizeRegion (core/raster/raster_region.h) on one thread around the poses' x, y: every
/// chunk with data whose square lies within radius_m of a pose.
Result<ChunkMap> rasterizeAround(const MapStore& store, const std::vector<Eigen::Vector3d>& centres,
                                 double radius_m, const RasterOptions& options, RasterStats& stats);

/// Mapping-pass points (KITTI directory with poses) within radius_m of `centre`, voxel
/// downsampled to voxel_m, in the map frame: the kind of map NDT/GICP localizers use.
Result<PointList> targetCloud(const std::string& mapping_dir, const Eigen::Vector3d& centre,
                              double radius_m, double voxel_m);

/// A prior offset from `truth`: uniform in a disc of radius r_m [m], heading within +-h_rad
/// [rad] (the benchmark's and kitti_check's seeded offsets).
Pose6 offsetPrior(const Eigen::Isometry3d& truth, double r_m, double h_rad, std::mt19937& rng);

/// Heading of a pose [rad] and the signed difference a - b of two headings in (-pi, pi]: the
/// error measures of the benchmark and kitti_check.
double yawOf(const Eigen::Isometry3d& T);
double angleDiff(double a, double b);

double median(std::vector<double> v);
double percentile(std::vector<double> v, double p);

}  // namespace bench
}  // namespace gmm_localization
