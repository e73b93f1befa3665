#include "evaluate/evaluate_map_frame.h"

#include <cmath>
#include <map>

#include "evaluate/evaluate_results.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/mapping/kitti_source.h"

namespace gmm_localization {
namespace eval {
namespace {

Result<std::vector<Eigen::Isometry3d>> readPoseList(const std::string& path) {
  auto poses = readKittiPoses(path);
  if (!poses) return Result<std::vector<Eigen::Isometry3d>>::failure(poses.error());
  std::vector<Eigen::Isometry3d> out;
  int expected = 0;
  for (const auto& [index, pose] : *poses) {
    if (index != expected++) {
      return Result<std::vector<Eigen::Isometry3d>>::failure(
          path + ": scan " + std::to_string(expected - 1) + " has no pose");
    }
    out.push_back(pose);
  }
  return out;
}

}  // namespace

Result<MapFrame> MapFrame::load(const std::string& directory) {
  const std::string map_path = directory + "/poses.txt";
  const std::string truth_path = directory + "/poses_truth.txt";
  auto map_poses = readPoseList(map_path);
  if (!map_poses) return Result<MapFrame>::failure("--map-poses: " + map_poses.error());
  auto true_poses = readPoseList(truth_path);
  if (!true_poses) {
    return Result<MapFrame>::failure("--map-poses: " + true_poses.error() +
                                     " (simulate --map-pose-error writes it beside poses.txt)");
  }
  auto frame = fromPoses(*map_poses, *true_poses);
  if (!frame) return Result<MapFrame>::failure("--map-poses " + directory + ": " + frame.error());
  return frame;
}

Result<MapFrame> MapFrame::fromPoses(const std::vector<Eigen::Isometry3d>& map_poses,
                                     const std::vector<Eigen::Isometry3d>& true_poses) {
  if (map_poses.empty() || map_poses.size() != true_poses.size()) {
    return Result<MapFrame>::failure(std::to_string(map_poses.size()) + " map poses against " +
                                     std::to_string(true_poses.size()) +
                                     " true poses (the same scans are needed, at least one)");
  }
  MapFrame f;
  for (size_t i = 0; i < map_poses.size(); ++i) {
    const Eigen::Isometry3d e = map_poses[i] * true_poses[i].inverse();
    const Eigen::AngleAxisd aa(e.linear());
    f.positions_.push_back(true_poses[i].translation());
    f.rotation_.push_back(aa.angle() * aa.axis());
    f.translation_.push_back(e.translation());
  }
  return f;
}

std::optional<PoseStamped2> MapFrame::toMapFrame(const PoseStamped2& truth) const {
  const Eigen::Vector2d at(truth.x, truth.y);
  double weight = 0.0;
  Eigen::Vector3d rot = Eigen::Vector3d::Zero(), trans = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < positions_.size(); ++i) {
    const double d = (positions_[i].head<2>() - at).norm();
    if (d > kRadiusM) continue;
    const double w = std::exp(-0.5 * (d / kSigmaM) * (d / kSigmaM));
    weight += w;
    rot += w * rotation_[i];
    trans += w * translation_[i];
  }
  if (!(weight > 0.0)) return std::nullopt;
  rot /= weight;
  trans /= weight;
  Eigen::Isometry3d e = Eigen::Isometry3d::Identity();
  if (rot.norm() > 0.0)
    e.linear() = Eigen::AngleAxisd(rot.norm(), rot.normalized()).toRotationMatrix();
  e.translation() = trans;
  return planar(fromIsometry(e * toIsometry(toPose6(truth))), truth.t);
}

void applyMapFrame(const MapFrame& frame, EvaluationResults& results) {
  for (EkfRow& row : results.ekf) {
    const auto m = frame.toMapFrame(row.truth);
    if (!m) continue;
    row.map_frame = {true, vehicleFrameError(*m, row.truth), vehicleFrameError(row.estimate, *m)};
  }
  for (MatchRow& row : results.matches) {
    if (!row.has_pose) continue;
    const auto m = frame.toMapFrame(row.truth);
    if (!m) continue;
    row.map_frame = {true, vehicleFrameError(*m, row.truth), vehicleFrameError(row.pose, *m)};
  }
}

}  // namespace eval
}  // namespace gmm_localization
