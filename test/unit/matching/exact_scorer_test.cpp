// ExactScorer (core/matching/exact_scorer.h) on the synthetic street: scoreReusing, the hill
// climb's scorer, equals score() up to the rounding of the point placement; reusing the cells
// of the pose a step was taken from changes no bit; and the placement keeps every height
// unchanged, bit for bit, for steps in x, y and heading, so those steps reuse most points.
#include "gmm_localization/core/matching/exact_scorer.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "gmm_localization/core/matching/hill_climb.h"
#include "support/street_fixture.h"

namespace gmm_localization {
namespace {

using ExactScorerTest = testing::StreetFixture;

/// Share of points whose block and height are those of `before` (the points reusable).
double sameKeys(const std::vector<CellBlockMemo>& a, const std::vector<CellBlockMemo>& b) {
  size_t same = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    same += a[i].cx == b[i].cx && a[i].cy == b[i].cy && a[i].z == b[i].z ? 1 : 0;
  }
  return static_cast<double>(same) / static_cast<double>(a.size());
}

TEST_F(ExactScorerTest, ReusingTheCellsOfTheLastPoseChangesNoBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int c = 0; c < 10; ++c) {
    const Pose6 truth = world_->streetPose(rng);
    const PointList scan = thinEvenly(world_->scan(truth, 35.0, 0.25, 0.0, 300 + c), 1500);
    const ExactScorer scorer(*chunks_, -6.0, truth.x, truth.y, 60.0);
    Pose6 pose = truth;
    pose.x += 0.1 * u(rng);
    pose.yaw += 0.01 * u(rng);
    pose.roll = 0.01 * u(rng);
    pose.pitch = 0.01 * u(rng);
    std::vector<CellBlockMemo> kept, fresh, reused;
    const double first = scorer.scoreReusing(scan, pose, nullptr, &kept);
    // The same value as score() up to the placement's rounding.
    EXPECT_NEAR(first, scorer.score(scan, pose), 1e-9 * std::abs(first)) << "case " << c;
    // One step along each axis, as the climb takes them.
    for (int axis = 0; axis < 6; ++axis) {
      Pose6 step = pose;
      double* coordinate[6] = {&step.x, &step.y, &step.z, &step.roll, &step.pitch, &step.yaw};
      *coordinate[axis] += axis < 3 ? 0.01 : 0.0005;
      const double without = scorer.scoreReusing(scan, step, nullptr, &fresh);
      const double with = scorer.scoreReusing(scan, step, &kept, &reused);
      EXPECT_EQ(with, without) << "case " << c << " axis " << axis;
      ASSERT_EQ(reused.size(), fresh.size());
      for (size_t i = 0; i < fresh.size(); ++i) {
        for (int k = 0; k < 9; ++k) ASSERT_EQ(reused[i].ll[k], fresh[i].ll[k]) << i;
      }
      // x, y, heading: the heights are unchanged and most points keep their block; z, roll and
      // pitch move every height.
      const double share = sameKeys(fresh, kept);
      if (axis == 0 || axis == 1 || axis == 5) {
        EXPECT_GT(share, 0.8) << "case " << c << " axis " << axis;
      } else {
        EXPECT_LT(share, 0.05) << "case " << c << " axis " << axis;
      }
    }
  }
}

}  // namespace
}  // namespace gmm_localization
