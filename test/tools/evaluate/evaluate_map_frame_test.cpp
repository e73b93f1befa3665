// The truth in the map's frame (src/tools/evaluate/evaluate_map_frame.h) on synthetic mapping
// poses with a known error: a constant error is reproduced exactly, errors of two places are
// kept apart, far from every mapping scan there is none, and the summary splits an estimate's
// error into the map's and the localization's own.
#include "evaluate/evaluate_map_frame.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "evaluate/evaluate_results.h"
#include "evaluate/evaluate_summary.h"

namespace gmm_localization {
namespace eval {
namespace {

Eigen::Isometry3d isometry(double x, double y, double z, double yaw, double pitch = 0.0,
                           double roll = 0.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

PoseStamped2 pose(double x, double y, double yaw) {
  PoseStamped2 p;
  p.x = x;
  p.y = y;
  p.yaw = yaw;
  return p;
}

/// Mapping scans every 2 m along y = 0 from x = 0 to 200, their map poses moved by `error`
/// (map pose = error * true pose).
std::pair<std::vector<Eigen::Isometry3d>, std::vector<Eigen::Isometry3d>> straightRun(
    const Eigen::Isometry3d& error, double x0 = 0.0, double x1 = 200.0) {
  std::vector<Eigen::Isometry3d> map, truth;
  for (double x = x0; x <= x1; x += 2.0) {
    truth.push_back(isometry(x, 0.0, 0.5, 0.0, 0.01, -0.02));
    map.push_back(error * truth.back());
  }
  return {map, truth};
}

TEST(EvaluateMapFrame, AConstantMapErrorIsReproducedExactly) {
  const Eigen::Isometry3d error = isometry(0.04, -0.03, 0.01, 0.2 * M_PI / 180.0, 0.001, 0.002);
  const auto [map, truth] = straightRun(error);
  auto frame = MapFrame::fromPoses(map, truth);
  ASSERT_TRUE(frame) << frame.error();
  const PoseStamped2 vehicle = pose(120.0, 3.0, 0.7);
  const auto in_map = frame->toMapFrame(vehicle);
  ASSERT_TRUE(in_map);
  // E T computed directly.
  const Eigen::Isometry3d expected = error * isometry(vehicle.x, vehicle.y, 0.0, vehicle.yaw);
  EXPECT_NEAR(in_map->x, expected.translation().x(), 1e-9);
  EXPECT_NEAR(in_map->y, expected.translation().y(), 1e-9);
  EXPECT_NEAR(in_map->z, expected.translation().z(), 1e-9);
  const Eigen::Matrix3d r = expected.linear();
  EXPECT_NEAR(in_map->yaw, std::atan2(r(1, 0), r(0, 0)), 1e-9);
  EXPECT_NEAR(in_map->yaw, 0.7 + 0.2 * M_PI / 180.0, 1e-5);  // pitch and roll tilt it a little
  // The rotation about the map origin moves a vehicle 120 m away by about 120 m x 0.2 deg.
  EXPECT_GT(std::hypot(in_map->x - vehicle.x, in_map->y - vehicle.y), 0.3);
}

TEST(EvaluateMapFrame, TwoPlacesKeepTheirOwnErrorAndNothingIsInventedFarAway) {
  auto [map_a, truth_a] = straightRun(isometry(0.05, 0.0, 0.0, 0.0), 0.0, 100.0);
  const auto [map_b, truth_b] = straightRun(isometry(-0.05, 0.02, 0.0, 0.0), 400.0, 500.0);
  map_a.insert(map_a.end(), map_b.begin(), map_b.end());
  truth_a.insert(truth_a.end(), truth_b.begin(), truth_b.end());
  auto frame = MapFrame::fromPoses(map_a, truth_a);
  ASSERT_TRUE(frame) << frame.error();
  const auto a = frame->toMapFrame(pose(50.0, 0.0, 0.0));
  const auto b = frame->toMapFrame(pose(450.0, 0.0, 0.0));
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(a->x - 50.0, 0.05, 1e-9);
  EXPECT_NEAR(b->x - 450.0, -0.05, 1e-9);
  EXPECT_NEAR(b->y, 0.02, 1e-9);
  // 250 m from both runs, and beside a run's end by more than the radius: no map there.
  EXPECT_FALSE(frame->toMapFrame(pose(250.0, 0.0, 0.0)));
  EXPECT_FALSE(frame->toMapFrame(pose(50.0, MapFrame::kRadiusM + 1.0, 0.0)));
}

TEST(EvaluateMapFrame, MismatchedOrMissingPosesAreRefusedWithTheReason) {
  const auto [map, truth] = straightRun(Eigen::Isometry3d::Identity());
  std::vector<Eigen::Isometry3d> shorter(truth.begin(), truth.end() - 1);
  auto frame = MapFrame::fromPoses(map, shorter);
  ASSERT_FALSE(frame);
  EXPECT_NE(frame.error().find("the same scans"), std::string::npos) << frame.error();
  EXPECT_FALSE(MapFrame::fromPoses({}, {}));
  // A directory without poses_truth.txt names the file and the simulate option.
  const std::string dir = ::testing::TempDir() + "map_frame_no_truth";
  std::system(("mkdir -p " + dir).c_str());
  std::ofstream(dir + "/poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::remove((dir + "/poses_truth.txt").c_str());
  auto loaded = MapFrame::load(dir);
  ASSERT_FALSE(loaded);
  EXPECT_NE(loaded.error().find("poses_truth.txt"), std::string::npos) << loaded.error();
  EXPECT_NE(loaded.error().find("--map-pose-error"), std::string::npos) << loaded.error();
  std::ofstream(dir + "/poses_truth.txt") << "1 0 0 0.1 0 1 0 0 0 0 1 0\n";
  loaded = MapFrame::load(dir);
  ASSERT_TRUE(loaded) << loaded.error();
  EXPECT_EQ(loaded->size(), 1u);
}

TEST(EvaluateMapFrame, TheSummarySplitsTheErrorIntoTheMapsAndTheLocalizations) {
  // The map is 6 cm east of the world along a road driven east; an estimate that fits the map
  // exactly is 6 cm ahead of the truth and 0 cm off in the map's frame.
  const Eigen::Isometry3d error = isometry(0.06, 0.0, 0.0, 0.0);
  const auto [map, truth] = straightRun(error);
  auto frame = MapFrame::fromPoses(map, truth);
  ASSERT_TRUE(frame) << frame.error();
  EvaluationResults r;
  r.info.mode = "bag";
  r.info.dataset = "downtown";
  r.info.map_poses = "mapping";
  for (int k = 0; k < 50; ++k) {
    EkfRow row;
    row.t = 0.1 * k;
    row.truth = pose(20.0 + k, 0.0, 0.0);
    row.estimate = pose(20.06 + k, 0.01, 0.0);  // fits the map, 1 cm to the left
    row.error = vehicleFrameError(row.estimate, row.truth);
    r.ekf.push_back(row);
    MatchRow m;
    m.outcome = "accepted";
    m.has_pose = true;
    m.truth = row.truth;
    m.pose = pose(20.06 + k, -0.02, 0.0);
    m.error = vehicleFrameError(m.pose, m.truth);
    r.matches.push_back(m);
  }
  applyMapFrame(*frame, r);
  const Summary s = summarizeResults(r);
  EXPECT_NEAR(s.ekf.rms_longitudinal_m, 0.06, 1e-9);
  EXPECT_NEAR(s.ekf_in_map.rms_longitudinal_m, 0.0, 1e-9);
  EXPECT_NEAR(s.ekf_in_map.rms_lateral_m, 0.01, 1e-9);
  EXPECT_NEAR(s.raw_in_map.rms_lateral_m, 0.02, 1e-9);
  EXPECT_NEAR(s.map_error.rms_longitudinal_m, 0.06, 1e-9);
  EXPECT_EQ(s.ekf_in_map.count, 50u);
  const std::string md = summaryMarkdown(r, s);
  EXPECT_NE(md.find("EKF output against the truth in the map's frame | 0.0 cm | 1.0 cm"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("the map's own error along the drive (its poses against their truth) | 6.0 cm"),
            std::string::npos)
      << md;
  const std::string json = summaryJson(r, s);
  EXPECT_NE(json.find("\"map_error\": {\"count\": 50"), std::string::npos) << json;
  // Without --map-poses the rows and the JSON keys say there is none.
  r.info.map_poses.clear();
  EXPECT_EQ(summaryMarkdown(r, s).find("map's frame"), std::string::npos);
  EXPECT_NE(summaryJson(r, s).find("\"map_error\": null"), std::string::npos);
}

}  // namespace
}  // namespace eval
}  // namespace gmm_localization
