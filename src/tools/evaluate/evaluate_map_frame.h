#pragma once
// The truth in the map's own frame, for a map built from poses that were not exact.
//
// A map built from mapping-pass poses P_i (a SLAM back end's, `poses.txt`) whose true values
// are T_i (`poses_truth.txt`, written by `simulate --map-pose-error`) places a world point w
// seen from scan i at P_i T_i^-1 w = E_i w: near scan i the map is the world moved by E_i. A
// localizer that fits that part of the map perfectly reports E T for a vehicle whose true pose
// is T. So the error of an estimate X splits into the map's error (E T against T) and the
// localization's own error (X against E T): `evaluate --map-poses DIR` reports both beside the
// error against the exact truth.
//
// E at a place is the weighted mean of the E_i of the mapping scans around it (Gaussian weight
// over their distance, sigma kSigmaM; the rotation averaged as rotation vectors, which is exact
// enough for errors of a few tenths of a degree). It is an approximation: the map of a cell
// blends every scan that saw it, from up to about 100 m.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "evaluate/evaluate_metrics.h"
#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace eval {

class MapFrame {
 public:
  static constexpr double kSigmaM = 10.0;   ///< weight sigma over the distance to a scan [m]
  static constexpr double kRadiusM = 30.0;  ///< scans farther than this are left out [m]

  /// Reads `<dir>/poses.txt` (the poses the map was built from) and `<dir>/poses_truth.txt`;
  /// fails naming the file, or when the two do not hold the same scans.
  static Result<MapFrame> load(const std::string& directory);
  /// From the two pose lists directly (same length, same order; at least one).
  static Result<MapFrame> fromPoses(const std::vector<Eigen::Isometry3d>& map_poses,
                                    const std::vector<Eigen::Isometry3d>& true_poses);

  /// The pose of `truth` in the map's frame (E truth); nullopt where no mapping scan is within
  /// kRadiusM (the map holds nothing there).
  std::optional<PoseStamped2> toMapFrame(const PoseStamped2& truth) const;
  size_t size() const { return positions_.size(); }

 private:
  std::vector<Eigen::Vector3d> positions_;  ///< true positions of the mapping scans
  std::vector<Eigen::Vector3d> rotation_;   ///< E_i's rotation vector [rad]
  std::vector<Eigen::Vector3d> translation_;
};

struct EvaluationResults;
/// Fills the map-frame errors of every EKF row and every match with a pose (rows where the
/// map holds nothing keep map_frame.valid false).
void applyMapFrame(const MapFrame& frame, EvaluationResults& results);

}  // namespace eval
}  // namespace gmm_localization
