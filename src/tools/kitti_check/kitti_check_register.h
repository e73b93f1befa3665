#pragma once
// Leave-one-out registration of real keyframes (the benchmark on real scans): for each keyframe, a
// Gaussian mixture map from the others, and registrations of the held-out scan from seeded
// random offsets around its SLAM pose by our Registration (paper Algorithm 1) and by PCL's NDT
// and GICP (the benchmark's peers, src/tools/bench/bench_peers.h) started at the same offset
// poses. Roll and pitch of every prior are the SLAM pose's (what an IMU gives), z is the SLAM
// pose's; x, y and heading are offset.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_data.h"
#include "bench/bench_peers.h"
#include "evaluate/evaluate_results.h"
#include "gmm_localization/core/matching/registration.h"
#include "gmm_localization/core/raster/raster_options.h"
#include "kitti_check/kitti_check_data.h"

namespace gmm_localization {
namespace kitti_check {

/// A search window with the offsets drawn inside it.
struct WindowSpec {
  std::string name;
  double half_m = 12.5;      ///< search window half extent in x and y [m]
  double half_deg = 15.0;    ///< heading half extent [deg]
  double offset_m = 10.0;    ///< offsets uniform in a disc of this radius [m]
  double offset_deg = 15.0;  ///< and uniform within +- this heading [deg]
};

struct LooOptions {
  KittiInput data;            ///< the keyframes (loadKeyframes)
  std::string work_dir;       ///< maps are written to <work_dir>/loo_<index>
  std::vector<int> held_out;  ///< keyframes to register (empty: all)
  int offsets = 100;          ///< offsets per keyframe and window
  uint32_t seed = 1;
  std::vector<WindowSpec> windows;  ///< default: paper window and tracking window
  bool ours = true;
  bool peers = true;
  bench::PeerOptions peer;           ///< the benchmark's defaults unless changed
  double peer_target_voxel_m = 0.5;  ///< as the benchmark's target clouds
  double raster_radius_m = 110.0;    ///< chunks with data within this are rasterized [m]
  double map_blur_sigma_m = 0.1;     ///< the fold maps' blur (build_map's default) [m]
  double grid_shift_m = 0.0;         ///< the fold maps' cell grid shifted by this in x, y [m]
  RegistrationOptions registration;
  RasterOptions raster;
};

/// The paper's window (25 m x 25 m, +-15 deg, offsets within 10 m / 15 deg) and the tracking
/// window (+-2 m, +-3 deg, offsets within 1.5 m / 2.5 deg, as bench_registration).
std::vector<WindowSpec> defaultWindows();

/// One registration.
struct Trial {
  int keyframe = 0;
  std::string window;   ///< WindowSpec::name, or "SLAM pose" for the zero-offset run
  std::string matcher;  ///< "ours", "PCL NDT", "PCL GICP"
  double offset_m = 0.0, offset_deg = 0.0;  ///< initial error
  bool matched = false;                     ///< a pose was returned
  std::string failure;                      ///< reason when not matched
  double error_m = 0.0;                     ///< horizontal error against the SLAM pose [m]
  double error_deg = 0.0;                   ///< heading error [deg]
  double error_z_m = 0.0;                   ///< |z error| [m]
  double error_long_m = 0.0;  ///< signed error along the SLAM pose's heading (x forward) [m]
  double error_lat_m = 0.0;   ///< signed error across it (y left) [m]
  /// ours: the same errors of the search's discrete optimum, before the hill climb refines it.
  double discrete_error_m = 0.0, discrete_error_long_m = 0.0, discrete_error_lat_m = 0.0;
  double seconds = 0.0;               ///< wall time of the match, one thread
  double cpu_seconds = 0.0;           ///< process CPU time of the match (robust to a busy machine)
  RegistrationTiming stages;          ///< ours: time per stage (search_s: the search)
  double evaluations_fraction = 0.0;  ///< ours: node scores / exhaustive poses
  /// ours: the certificate, protection level and the SLAM pose's score deficit (the truth as
  /// MatchRequest::reference), as `evaluate` reports them (evaluate_integrity.h).
  eval::IntegrityFields integrity;
  bool success() const { return matched && error_m < 0.5 && error_deg < 1.0; }
};

/// One fold: the map of the other keyframes and how much of the held-out scan it covers.
struct Fold {
  int keyframe = 0;
  std::vector<int> map_keyframes;
  double nearest_map_keyframe_m = 0.0;  ///< distance to the closest mapped keyframe [m]
  uint64_t map_cells = 0;               ///< cells with data
  double overlap = 0.0;  ///< share of the scan's 0.2 m voxels over non-empty map cells (truth)
};

struct LooReport {
  std::vector<Fold> folds;
  std::vector<Trial> trials;
  KittiScans data;  ///< how the keyframes were read
};

/// Runs every fold; progress lines go to stderr. Fails on unreadable data or a map build error.
Result<LooReport> runLeaveOneOut(const LooOptions& options);

/// Seeded prior offsets: the benchmark's own.
using bench::offsetPrior;

/// Horizontal [m] (also split along and across truth's heading), heading [deg] and |z| [m]
/// errors of `pose` against `truth`.
void poseErrors(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& truth, Trial& t);

}  // namespace kitti_check
}  // namespace gmm_localization
