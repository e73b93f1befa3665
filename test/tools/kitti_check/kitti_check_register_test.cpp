// kitti_check's leave-one-out registration on the real KITTI 07 keyframes (skipped when
// ../shared/data/real is absent), and its offset generator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "gmm_localization/core/common/types.h"
#include "kitti_check/kitti_check_register.h"

using namespace gmm_localization;
using namespace gmm_localization::kitti_check;

TEST(KittiCheckRegister, OffsetsStayInTheirDiscAndHeadingRange) {
  std::mt19937 rng(5);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.translation() = Eigen::Vector3d(3, -2, 0.5);
  truth.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  double largest = 0.0;
  for (int i = 0; i < 500; ++i) {
    const Pose6 p = offsetPrior(truth, 10.0, 15.0 * M_PI / 180.0, rng);
    Trial t;
    poseErrors(toIsometry(p), truth, t);
    EXPECT_LE(t.error_m, 10.0 + 1e-9);
    EXPECT_LE(t.error_deg, 15.0 + 1e-6);
    EXPECT_NEAR(t.error_z_m, 0.0, 1e-9);
    largest = std::max(largest, t.error_m);
  }
  EXPECT_GT(largest, 9.0);  // the disc is filled, not a smaller one
}

TEST(KittiCheckRegister, LeaveOneOutRecoversTheMiddleKeyframe) {
  const std::string dir = std::string(GMM_SHARED_DATA_DIR) + "/real/kitti07_keyframes";
  if (!std::filesystem::exists(dir + "/graph.txt")) {
    GTEST_SKIP() << "real data absent: " << dir << " (see ../shared/data/real/README.md)";
  }
  const std::filesystem::path work =
      std::filesystem::temp_directory_path() / ("kitti_check_test_" + std::to_string(getpid()));
  LooOptions o;
  o.data.dir = dir;
  o.work_dir = work.string();
  o.held_out = {2};
  o.offsets = 3;
  o.peers = false;
  auto report = runLeaveOneOut(o);
  std::filesystem::remove_all(work);
  ASSERT_TRUE(report.ok()) << report.error();
  ASSERT_EQ(report->folds.size(), 1u);
  EXPECT_EQ(report->folds[0].map_keyframes, (std::vector<int>{0, 1, 3, 4}));
  EXPECT_GT(report->folds[0].overlap, 0.5);
  // From the SLAM pose and from 3 offsets in each of the two windows: all within 10 cm and
  // 0.2 deg of the SLAM pose (measured: about 1-2 cm and 0.03 deg).
  ASSERT_EQ(report->trials.size(), 7u);
  for (const Trial& t : report->trials) {
    ASSERT_TRUE(t.matched) << t.window << ": " << t.failure;
    EXPECT_LT(t.error_m, 0.1) << t.window << " from " << t.offset_m << " m";
    EXPECT_LT(t.error_deg, 0.2) << t.window << " from " << t.offset_deg << " deg";
    // The integrity fields evaluate reports: a certified match lies within its protection
    // level, and the SLAM pose (inside every window here) has its score deficit measured.
    EXPECT_TRUE(t.integrity.valid) << t.window;
    if (t.integrity.certified) {
      EXPECT_LE(t.error_m, t.integrity.protection_xy_m) << t.window;
    }
    EXPECT_TRUE(std::isfinite(t.integrity.truth_deficit_per_point)) << t.window;
    // The discrete optimum is reported too: started at the SLAM pose the search's grid is
    // centred on it, so its optimum is that very cell; from an offset it lies on the 0.2 m grid
    // of the offset start, within a cell diagonal of the SLAM pose here.
    if (t.window == "SLAM pose") {
      EXPECT_NEAR(t.discrete_error_m, 0.0, 1e-9);
    } else {
      EXPECT_LT(t.discrete_error_m, 0.2 * std::sqrt(2.0)) << t.window;
      EXPECT_GT(t.discrete_error_m, 0.0) << t.window;  // off the grid of the truth
    }
  }
}
