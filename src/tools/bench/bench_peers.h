#pragma once
// The point-cloud matchers our search is compared with, from PCL: NormalDistributionsTransform
// (behind hdl_localization and Autoware's NDT matcher) and GeneralizedIterativeClosestPoint,
// each started at the same offset pose as our search.

#include <string>

#include <Eigen/Geometry>

#include "gmm_localization/core/matching/scan_filter.h"

namespace gmm_localization {
namespace bench {

struct PeerOptions {
  double source_voxel_m = 0.5;    ///< scan downsampling
  double ndt_resolution_m = 1.0;  ///< NDT cell size (Autoware and hdl_localization: 1.0)
  double ndt_step_size_m = 0.1;
  double epsilon = 0.01;  ///< GICP: transformation epsilon is 0.1 x this
  /// NDT transformation epsilon. PCL 1.13 compares it with the squared update norm, which the
  /// step size bounds (0.1^2 = 0.01): hdl_localization's 0.01 would stop NDT after its first
  /// iteration. 1e-4 is the same 0.01 m on the update norm.
  double ndt_epsilon = 1e-4;
  int max_iterations = 64;
  double gicp_max_correspondence_m = 5.0;
};

struct PeerResult {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  double seconds = 0.0;
  bool converged = false;
};

class PeerMatcher {
 public:
  enum class Kind { kNdt, kGicp };
  PeerMatcher(Kind kind, const PeerOptions& options);
  ~PeerMatcher();
  std::string name() const;
  /// Target cloud in the map frame; the time to build its structures is not counted per match.
  void setTarget(const PointList& map_points);
  /// Registers the scan (base_link) from the guess (base_link in map).
  PeerResult align(const PointList& scan, const Eigen::Isometry3d& guess);

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace bench
}  // namespace gmm_localization
