#pragma once
// MapPoseError: turns the exact poses of a mapping pass into those a SLAM back end would
// deliver, so build_map is fed a map that is not built from perfect poses. The error is smooth
// along the path (a map from jittered poses would be a different, unrealistic error):
//   error(s) = residual(s) + drift(s), s = distance travelled,
//   residual: a smooth sum of long-wavelength sinusoids per axis (x, y, z, roll, pitch, yaw) whose
//             RMS (norm over the three axes) is residual_m / residual_deg;
//   drift:    a random walk per axis driven by distance (std drift_*_per_100m after 100 m),
//             pinned back to zero at the start and at every loop closure (a pose within
//             loop_radius_m of one at least min_loop_m of path earlier), the correction spread
//             linearly between closures as a pose-graph optimisation would spread it.
// Error applied in the map frame: p' = p + dp, R' = R_err * R. Deterministic for a seed.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace sim {

enum class MapPoseErrorMode { kNone, kRealistic };

/// "none" or "realistic"; anything else is a failure naming the value.
Result<MapPoseErrorMode> parseMapPoseErrorMode(const std::string& name);

struct MapPoseErrorConfig {
  MapPoseErrorMode mode = MapPoseErrorMode::kNone;
  double drift_m_per_100m = 0.03;    ///< random-walk std per axis after 100 m, between closures
  double drift_deg_per_100m = 0.05;  ///< same for roll, pitch, yaw
  double residual_m = 0.05;          ///< RMS position residual (norm over x, y, z)
  double residual_deg = 0.2;         ///< RMS attitude residual (norm over roll, pitch, yaw)
  double loop_radius_m = 10.0;       ///< a revisit closer than this closes a loop
  double min_loop_m = 50.0;          ///< path length a loop must have before it can close
  uint64_t seed = 1;
  /// Non-negative, finite values; loop radius and minimum loop length > 0.
  Status validate() const;
};

class MapPoseError {
 public:
  explicit MapPoseError(const MapPoseErrorConfig& config) : config_(config) {}
  /// The SLAM-like poses for `truth` (in path order); mode none returns `truth` unchanged.
  std::vector<Eigen::Isometry3d> apply(const std::vector<Eigen::Isometry3d>& truth) const;
  /// Indices of `truth` that close a loop (where the drift is pinned back to zero).
  std::vector<size_t> closures(const std::vector<Eigen::Isometry3d>& truth) const;

 private:
  MapPoseErrorConfig config_;
};

}  // namespace sim
}  // namespace gmm_localization
