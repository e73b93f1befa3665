#pragma once
// Data for the registration benchmark and kitti_check: KITTI-style data sets as users have them
// (a KITTI odometry sequence, the simulator's KITTI output, keyframe dumps), test scans with
// ground truth from one, the rasterized map around them, and target point clouds for the
// point-cloud peers (NDT, GICP) from the mapping scans.

#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_store.h"
#include "gmm_localization/core/mapping/kitti_source.h"
#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/matching/search_problem.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {
namespace bench {

/// A KITTI-style data set: scans DIR/velodyne/NNNNNN.bin, DIR/NNNNNN.bin or
/// DIR/NNNNNN/points.bin (core/mapping/kitti_source.h), their poses, optionally a KITTI
/// calibration. Read with the same meaning as build_map's --kitti, --poses, --kitti-calib and
/// --kitti-fields, so a map built from it and the poses read here share one frame.
struct KittiInput {
  std::string dir;
  std::string poses_file;  ///< empty: DIR/graph.txt, else DIR/poses.txt
  /// KITTI odometry calib.txt (its `Tr:` line, readKittiCalibTr): the poses are camera-0 poses,
  /// the scans' poses become Tr^-1 * pose * Tr (map frame: the first Velodyne frame, z up), as
  /// build_map --kitti-calib. Empty: the poses are the sensor's.
  std::string calib_file;
  KittiFields fields = KittiFields::kAuto;  ///< record layout; kAuto: see openKittiInput
};

/// The scans of a KittiInput that have both a pose and a file.
struct KittiScans {
  KittiSourceOptions source;                 ///< resolved: layout, poses file, calibration
  std::vector<KittiScanSource::Scan> scans;  ///< sensor in map per scan, by index
  size_t poses = 0;                          ///< poses in the poses file
  std::vector<int> missing;                  ///< indices with a pose but no scan file (skipped)
  std::string layout;      ///< how the records are read and why (one sentence, for the user)
  bool ambiguous = false;  ///< kAuto guessed: every file size fits both layouts
};

/// Opens a data set. Scans without a file are skipped (listed in `missing`); fails when no
/// scan has both. The record layout is `fields` when given, else: x,y,z,intensity for scans
/// under velodyne/ (KITTI's, as kitti_source.h), x,y,z for NNNNNN/points.bin (the keyframe
/// dumps), otherwise what the file sizes allow (12 vs 16 bytes per point; sizes that fit both:
/// x,y,z,intensity, flagged `ambiguous`). A file whose size is not a multiple of the record
/// size is an error naming it.
Result<KittiScans> openKittiInput(const KittiInput& input);

/// "auto" | "xyz" | "xyzi".
Result<KittiFields> parsePointFormat(const std::string& text);
const char* pointFormatName(KittiFields fields);

struct BenchScan {
  int index = 0;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();  ///< base_link in map
  PointList points;                                         ///< base_link [m]
  /// One per point when the records are x,y,z,intensity (the reflectivity and fused
  /// methods need it), else empty.
  std::vector<float> intensity;
};

/// `count` scans evenly spread over the data set's scans that have a file (all when
/// count <= 0); `data` gets the opened data set (layout, skipped poses).
Result<std::vector<BenchScan>> loadScans(const KittiInput& input, int count, KittiScans* data);

struct RasterStats {
  size_t chunks = 0;
  double seconds = 0.0;  ///< total rasterization time (tiles loaded beforehand)
  size_t bytes = 0;
};

/// rasterizeRegion (core/raster/raster_region.h) on one thread around the poses' x, y: every
/// chunk with data whose square lies within radius_m of a pose.
Result<ChunkMap> rasterizeAround(const MapStore& store, const std::vector<Eigen::Vector3d>& centres,
                                 double radius_m, const RasterOptions& options, RasterStats& stats);

/// Which mapping scans make the peers' target cloud around a test scan.
struct PeerTargetOptions {
  /// Mapping scans whose index is a multiple of this (5: the simulator's mapping pass at
  /// 10 Hz overlaps heavily; 1: every scan).
  int stride = 5;
  /// Leave out mapping scans whose index is within this of the test scan's (0: the test scan
  /// itself; for a map and test scans from one sequence); negative: leave none out.
  int exclude = -1;
  double radius_m = 80.0;  ///< points within this of the test scan, from scans within half
  double voxel_m = 0.5;    ///< voxel downsampling of the target
};

/// One line describing the selection, for the report.
std::string describe(const PeerTargetOptions& options);

/// Mapping points around the test scan at `centre` (index `test_index`), chosen by `options`,
/// in the map frame: the kind of map NDT/GICP localizers use. Fails when no mapping scan is
/// selected.
Result<PointList> targetCloud(const KittiScans& mapping, const Eigen::Vector3d& centre,
                              int test_index, const PeerTargetOptions& options);

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
