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

/// A street scan of 1,500 points seen from a random street pose, and a scorer around it.
struct StreetCase {
  Pose6 truth;
  PointList scan;
  ExactScorer scorer;
};

class ExactScorerTest : public testing::StreetFixture {
 protected:
  static StreetCase streetCase(std::mt19937& rng, int noise_seed) {
    const Pose6 truth = world_->streetPose(rng);
    return {truth, thinEvenly(world_->scan(truth, 35.0, 0.25, 0.0, noise_seed), 1500),
            ExactScorer(*chunks_, -6.0, truth.x, truth.y, 60.0)};
  }
};

/// The same six coordinates, bit for bit.
void expectSamePose(const Pose6& a, const Pose6& b, int c) {
  const double Pose6::*coordinates[6] = {&Pose6::x,    &Pose6::y,     &Pose6::z,
                                         &Pose6::roll, &Pose6::pitch, &Pose6::yaw};
  for (int k = 0; k < 6; ++k) EXPECT_EQ(a.*coordinates[k], b.*coordinates[k]) << "case " << c;
}

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
    const StreetCase k = streetCase(rng, 300 + c);
    const PointList& scan = k.scan;
    const ExactScorer& scorer = k.scorer;
    Pose6 pose = k.truth;
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

TEST_F(ExactScorerTest, ASecondMemoOfTheSameStepServesTheStepsThatMoveEveryHeight) {
  // The climb's pattern: a step up in z is tried, the climb moves in x instead, and tries z up
  // again. The pose it stands on has none of the heights of that trial; the earlier z trial has
  // them for every point still in its block. Taken from there, not one bit changes.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int c = 0; c < 6; ++c) {
    const StreetCase k = streetCase(rng, 400 + c);
    const PointList& scan = k.scan;
    const ExactScorer& scorer = k.scorer;
    Pose6 pose = k.truth;
    pose.x += 0.1 * u(rng);
    pose.roll = 0.01 * u(rng);
    const double step = c % 2 == 0 ? 0.01 : -0.02;
    for (int axis : {2, 3, 4}) {  // z, roll, pitch
      std::vector<CellBlockMemo> kept, first_trial, moved, fresh, reused;
      scorer.scoreReusing(scan, pose, nullptr, &kept);
      auto along = [&](Pose6 p) {
        double* coordinate[6] = {&p.x, &p.y, &p.z, &p.roll, &p.pitch, &p.yaw};
        *coordinate[axis] += axis == 2 ? 0.02 : 0.001;
        return p;
      };
      scorer.scoreReusing(scan, along(pose), &kept, &first_trial);
      Pose6 next = pose;
      next.x += step;
      scorer.scoreReusing(scan, next, &kept, &moved);
      const double without = scorer.scoreReusing(scan, along(next), nullptr, &fresh);
      const double with =
          scorer.scoreReusing(scan, along(next), &moved, &reused, nullptr, &first_trial);
      EXPECT_EQ(with, without) << "case " << c << " axis " << axis;
      for (size_t i = 0; i < fresh.size(); ++i) {
        for (int k = 0; k < 9; ++k) ASSERT_EQ(reused[i].ll[k], fresh[i].ll[k]) << i;
      }
      EXPECT_LT(sameKeys(fresh, moved), 0.05) << "case " << c << " axis " << axis;
      EXPECT_GT(sameKeys(fresh, first_trial), 0.8) << "case " << c << " axis " << axis;
    }
  }
}

TEST_F(ExactScorerTest, TheClimbWithItsMemosTakesThePathOfOneThatScoresEveryPoseAfresh) {
  // hillClimb on the scorer reuses cells from several memos; the same climb on an objective
  // that evaluates every point's cells at every pose must take the same steps and end on the
  // same pose with the same score, bit for bit (both on all points and coarse-to-fine).
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int c = 0; c < 4; ++c) {
    const StreetCase k = streetCase(rng, 500 + c);
    const PointList& scan = k.scan;
    const ExactScorer& scorer = k.scorer;
    Pose6 start = k.truth;
    start.x += 0.12 * u(rng);
    start.y += 0.12 * u(rng);
    start.z += 0.1 * u(rng);
    start.yaw += 0.008 * u(rng);
    start.pitch += 0.01 * u(rng);
    for (size_t coarse_points : {size_t{0}, size_t{750}}) {
      HillClimbOptions o;
      o.coarse_points = coarse_points;
      const HillClimbOutcome memo = hillClimb(scorer, scan, start, o);
      ClimbObjective afresh;
      std::vector<CellBlockMemo> scratch;
      afresh.full = [&](const Pose6& p) { return scorer.scoreReusing(scan, p, nullptr, &scratch); };
      const PointList coarse = thinEvenly(scan, coarse_points);
      if (coarse_points > 0) {
        afresh.coarse = [&](const Pose6& p) {
          return scorer.scoreReusing(coarse, p, nullptr, &scratch);
        };
      }
      const HillClimbOutcome plain = hillClimb(afresh, start, o);
      EXPECT_EQ(memo.evaluations, plain.evaluations) << "case " << c;
      EXPECT_EQ(memo.score, plain.score) << "case " << c;
      expectSamePose(memo.pose, plain.pose, c);
      EXPECT_GE(memo.score, memo.score_start);
      EXPECT_GT(memo.evaluations, 20) << "case " << c;  // a climb, not a stop at the start
    }
  }
}

}  // namespace
}  // namespace gmm_localization
